"""Offline build cost per stage and peak memory, for the four examples (issue 40, BENCHMARKS §14).

    .venv/bin/python scripts/build_cost.py [--tool target/release/fmu-build]
        [--baseline-tool PATH] [--examples kurokawa_spur small_spur kurokawa_helical small_helical]

Each example is built on its defaults (`fmu-build build SPEC -o …`) under `/usr/bin/time -v`,
the baseline tool first when given (a build of an earlier commit: the ratio is then from one
script run on one machine). A stage's duration runs from its start to the next start of the same
gear (the two gears' FE stages run side by side); `fmu-build` prints the start times. Prints one
markdown table; a stage a tool did not mark the end of is shown as "≤" the time to the next mark.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ("kurokawa_spur", "small_spur", "kurokawa_helical", "small_helical")
GEAR_STAGES = ("FE model", "attachment modes", "eigenmodes", "shapes and invariants")


def build(tool: Path, spec: Path, out: Path) -> dict:
    proc = subprocess.run(["/usr/bin/time", "-v", str(tool), "build", str(spec), "-o", str(out)],
                          capture_output=True, text=True, cwd=REPO_ROOT)
    if proc.returncode != 0:
        raise SystemExit(f"{tool} build {spec} failed:\n{proc.stdout}\n{proc.stderr}")
    line = next(l for l in proc.stdout.splitlines() if l.startswith("build stages (start times):"))
    body, done = line.split(": ", 1)[1].rsplit("; done ", 1)
    events = [(float(m.group(1)), m.group(2)) for m in re.finditer(r"([0-9.]+) s ([^,]+)", body)]
    events.append((float(done.split()[0]), "done"))
    peak_kib = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", proc.stderr).group(1))
    estimate = next((float(m.group(1)) for _, name in events if (m := re.match(r"estimated peak ([0-9.]+) GB", name))), None)
    events = [e for e in events if not e[1].startswith("estimated peak")]
    return {"events": events, "wall_s": events[-1][0], "peak_gb": peak_kib * 1024 / 1e9, "estimate_gb": estimate}


def stage_seconds(events: list[tuple[float, str]], gear: int, stage: str) -> str:
    """From the start of `gear N: stage` to the next event of gear N or of the whole pair.

    The FE stages of the two gears run side by side; the shapes, one gear after the other, end
    at whatever comes next. A tool that does not mark a gear's end ("gear N: reduced") lets its
    last FE stage run to the pair's next stage, waiting for the other gear: shown as "≤"."""
    prefix = f"gear {gear}: "
    for i, (at, name) in enumerate(events):
        if not (name.startswith(prefix) and stage in name):
            continue
        sequential = stage == "shapes and invariants"
        for later_at, later in events[i + 1:]:
            if sequential or later.startswith(prefix) or not later.startswith("gear "):
                bound = "" if sequential or later.startswith(prefix) or later == "done" else "≤ "
                return f"{bound}{later_at - at:.1f}"
    return "—"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tool", type=Path, default=REPO_ROOT / "target" / "release" / "fmu-build")
    parser.add_argument("--baseline-tool", type=Path)
    parser.add_argument("--examples", nargs="+", default=list(EXAMPLES))
    parser.add_argument("--keep", type=Path, help="keep the built FMUs in this directory ({example}-{tool}.fmu)")
    args = parser.parse_args()
    tools = ([("baseline", args.baseline_tool)] if args.baseline_tool else []) + [("this", args.tool)]
    header = ["example", "tool", "build (s)", "peak (GB)", "estimated peak (GB)"] + [f"{s} g1 / g2 (s)" for s in GEAR_STAGES]
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    with tempfile.TemporaryDirectory() as tmp:
        for example in args.examples:
            spec = REPO_ROOT / "examples" / f"{example}.toml"
            for label, tool in tools:
                r = build(tool, spec, (args.keep or Path(tmp)) / f"{example}-{label}.fmu")
                print(f"{example} {label}: {r['events']}", file=sys.stderr, flush=True)
                cells = [f"{stage_seconds(r['events'], 1, s)} / {stage_seconds(r['events'], 2, s)}" for s in GEAR_STAGES]
                estimate = "—" if r["estimate_gb"] is None else f"{r['estimate_gb']:.1f}"
                print(f"| {example} | {label} | {r['wall_s']:.1f} | {r['peak_gb']:.1f} | {estimate} | " + " | ".join(cells) + " |",
                      flush=True)


if __name__ == "__main__":
    main()
