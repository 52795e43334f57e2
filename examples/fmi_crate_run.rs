//! A second FMI client: drives a gearfmu .fmu with the Rust `fmi` crate (an independent importer)
//! through the same scenario as the fmpy test `tests/python/test_second_client.py`, and writes the
//! outputs as CSV with round-trip precision so the two clients can be compared bit for bit.
//!
//! `cargo run --release --example fmi_crate_run -- target/fmu/KurokawaSpur.fmu out.csv`
//!
//! Scenario: 250 steps of 0.1 ms; tau_1 = 185 N·m; tau_2 = −20·w_2 (viscous load) from the
//! previous step's output.

use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::{CoSimulation, Common};
use gearfmu::interface::value_reference;
use std::io::Write;

const OUTPUTS: [&str; 6] = ["phi_1", "phi_2", "w_1", "w_2", "dte", "mesh_force"];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let (fmu, csv) = match args.as_slice() {
        [_, fmu, csv] => (fmu, csv),
        _ => return Err("usage: fmi_crate_run <file.fmu> <out.csv>".into()),
    };
    let vr = |name: &str| value_reference(name).ok_or(format!("no variable {name}"));
    let inputs = [vr("tau_1")?, vr("tau_2")?];
    let outputs: Vec<u32> = OUTPUTS.iter().map(|n| vr(n)).collect::<Result<_, _>>()?;

    let import: Fmi2Import = fmi::import::from_path(fmu)?;
    let mut instance = import.instantiate_cs("fmi-crate", false, true)?;
    instance.setup_experiment(None, 0.0, None).map_err(|e| format!("{e:?}"))?;
    instance.enter_initialization_mode().map_err(|e| format!("{e:?}"))?;
    instance.exit_initialization_mode().map_err(|e| format!("{e:?}"))?;

    let mut out = std::fs::File::create(csv)?;
    writeln!(out, "time,{}", OUTPUTS.join(","))?;
    let h = 1e-4;
    let mut values = vec![0.0; outputs.len()];
    let mut w_2 = 0.0;
    for k in 0..250 {
        let t = k as f64 * h;
        instance.set_real(&inputs, &[185.0, -20.0 * w_2]).map_err(|e| format!("{e:?}"))?;
        instance.do_step(t, h, true).map_err(|e| format!("{e:?}"))?;
        instance.get_real(&outputs, &mut values).map_err(|e| format!("{e:?}"))?;
        w_2 = values[3];
        let row: Vec<String> = values.iter().map(|v| format!("{v:?}")).collect();
        writeln!(out, "{:?},{}", t + h, row.join(","))?;
    }
    Ok(())
}
