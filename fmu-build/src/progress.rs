//! Progress of the long offline stages: an indicatif spinner on a terminal, plain timed lines off one.

use indicatif::ProgressBar;

/// Progress of a long command: an indicatif spinner on a terminal; off a terminal (a log file,
/// CI) plain lines on stderr, at most one a second, so a long build is never silent.
pub(crate) struct Progress {
    bar: ProgressBar,
    plain: bool,
    started: std::time::Instant,
    last_line: std::sync::Mutex<Option<std::time::Instant>>,
}

impl Progress {
    pub(crate) fn set_message(&self, message: impl Into<String>) {
        let message = message.into();
        if self.plain {
            let mut last = self.last_line.lock().unwrap_or_else(|p| p.into_inner());
            if last.is_none_or(|at| at.elapsed().as_secs_f64() >= 1.0) {
                eprintln!("[{:6.1} s] {message}", self.started.elapsed().as_secs_f64());
                *last = Some(std::time::Instant::now());
            }
        }
        self.bar.set_message(message);
    }

    /// A stage of the work: off a terminal always printed (stages are few; `set_message`'s
    /// chatty updates are thinned to one a second).
    pub(crate) fn stage(&self, message: String) {
        if self.plain {
            *self.last_line.lock().unwrap_or_else(|p| p.into_inner()) = None;
        }
        self.set_message(message);
    }

    pub(crate) fn finish_and_clear(&self) {
        self.bar.finish_and_clear();
    }
}

pub(crate) fn spinner(message: String) -> Progress {
    let bar = ProgressBar::new_spinner();
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    let progress = Progress {
        bar,
        plain: !std::io::IsTerminal::is_terminal(&std::io::stderr()),
        started: std::time::Instant::now(),
        last_line: Default::default(),
    };
    progress.set_message(message);
    progress
}
