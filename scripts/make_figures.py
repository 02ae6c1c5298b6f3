"""Reproduce the paper's figures and the Apophis study (make figures).

For each figure's scenario (tumble_ros/config/fig*.yaml, apophis_2029.yaml): run bringup
(simulate, compare with the paper's analytic solution, record to
recordings/figures/<name>.mcap), analyse the recording, write its PNGs to OUT/<name>/
and its summary to OUT/<name>/summary.txt; for apophis_2029 also the encounter
ensemble (tumble_ros.cli.encounter, 1000 bodies) into OUT/apophis_2029/encounter/ and the
same at the new depth (scripts/apophis_depth.py) into OUT/apophis_2029/depth/;
finally the index OUT/README.md that sets each figure beside the paper's caption.

OUT is build/figures/ (untracked: a figure run leaves the clone's tracked files as they were;
``make clean`` removes it). The figures in the repository, docs/figures/, are refreshed on
purpose with ``--out docs/figures`` (``make figures FIGURES_OUT=docs/figures``), then committed:
message counts and the last digits of some numbers differ from run to run and machine to machine.

    scripts/env.sh python scripts/make_figures.py [--out DIR] [fig3 fig9 apophis_2029 ...]
    (default: all, into build/figures/)
"""
from __future__ import annotations

import argparse
from pathlib import Path
import sys

from tumble_ros.analysis import analyze, format_summary, load_recording, write_figures
from tumble_ros.analysis.recording import stderr_progress
from tumble_ros.cli.encounter import main as encounter
from tumble_ros.nodes.bringup import format_result, run_bringup

from apophis_depth import main as apophis_depth  # scripts/: beside this file

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "tumble_ros" / "config"
#: Where a figure run writes (untracked); docs/figures/ is the published copy.
OUT = ROOT / "build" / "figures"
RECORDINGS = ROOT / "recordings" / "figures"

#: The paper's captions (its Fig 8 is printed as a second "Figure 6").
CAPTIONS = {
    "fig3": "Numerical and analytical solution E-L equation. a = 2; θ = 0.1; φ = 0.5; ωx0 = 0, ωy0 = 1; "
            "ωz0 = 30; ωs = 1; tk = 2 years, n = 1000.",
    "fig4": "Numerical and analytical (bold line) solution E-L equation. a = 0.5; θ = 0.1; φ = 0.5; ωx0 = 0, "
            "ωy0 = 1; ωz0 = 30; ωs = 1; tk = 2 years, n = 1000.",
    "fig5": "Numerical and analytical (bold line) solution E-L equation. a = 0.5; θ = 0.5; φ = 0.5; ωx0 = 0, "
            "ωy0 = 1; ωz0 = 30; ωs = 1; tk = 2 years, n = 1000.",
    "fig6": "Numerical and analytical (bold line) solution E-L equation. a = 3; θ = 0.5; φ = 0.5; ωx0 = 0, "
            "ωy0 = 1; ωz0 = 30; ωs = 1; tk = 2 years, n = 1000.",
    "fig7": "Numerical solution E-L equation. a = 3; θ = 0.9; φ = 0.5; ωx0 = 0.1, ωy0 = 0.1; ωz0 = 30; "
            "ωs = 1; tk = 2 years, n = 1000.",
    "fig8": "(printed as \"Figure 6\") Numerical solution E-L equation. a = 3; θ = 0.9; φ = 0.5; ωx0 = 0.1, "
            "ωy0 = 0.1; ωz0 = 30; ωs = 1; tk = 20 years, n = 1000.",
    "fig9": "Numerical solution E-L equation. a = 3; θ = 0.9; φ = 0.5; ωx0 = 0.1, ωy0 = 0.1; ωz0 = 30; "
            "ωs = 1; tk = 2000 years, n = 1000. Below wy vs. wx plot.",
    "fig10": "Simulation of impact interaction. Above R-K procedure, below \"ode\".",
    "apophis_2029": "(not in the paper) (99942) Apophis, a tumbler, through its Earth flyby of "
                    "2029-04-13 at 38,326 km: the Earth's tidal torque on the published spin state "
                    "(tumble_ros/config/apophis_2029.yaml cites every number).",
}
#: Each section's heading in the index.
TITLES = {name: name.replace("fig", "Figure ") for name in CAPTIONS if name.startswith("fig")}
TITLES["apophis_2029"] = "Apophis 2029 encounter"
NOTES = {
    "fig8": "Sampled every 0.02 yr (n = 1000 over 20 yr, as printed).",
    "fig9": "Sampled every 0.01 yr, not the paper's 2 yr (n = 1000 over 2000 yr), which aliases the "
            "~0.07-yr oscillation of ω⊥ (docs/paper.md, conventions).",
    "apophis_2029": "Above: the nominal tumbler (phase 0 of its cycle). Below: 1000 tumblers with the "
                    "same observed periods and pole, drawn over the phase of the tumbling cycle, the "
                    "turn about L and the moments of inertia (docs/physics.md, \"Apophis 2029\"; "
                    "the comparison with Benson et al. 2023 is there).",
    "fig10": "The paper prints no parameters for this figure: the Fig 4 body receives a 3·10⁻⁷-yr pulse "
             "about body y at t = 1 yr (config/fig10.yaml). Integrated with the adaptive dop853: the "
             "integration is split at the pulse's edges, so unlike the paper's \"ode\" it does not step "
             "over the pulse (docs/physics.md).",
}


def make(name: str, root: Path = OUT) -> str:
    """Record, analyse and draw one figure into root/<name>/; return its section of the index."""
    RECORDINGS.mkdir(parents=True, exist_ok=True)
    recording = RECORDINGS / f"{name}.mcap"
    recording.unlink(missing_ok=True)
    print(f"== {name}", file=sys.stderr)
    result = run_bringup(CONFIG / f"{name}.yaml", output=recording)
    print(format_result(result), file=sys.stderr)
    rec = load_recording(recording, progress=stderr_progress())
    summary = analyze(rec)
    out = root / name
    out.mkdir(parents=True, exist_ok=True)
    for old in out.glob("*.png"):
        old.unlink()
    figures = write_figures(rec, out, summary)
    text = format_summary(summary).replace(str(recording), f"recordings/figures/{name}.mcap")
    (out / "summary.txt").write_text(text + "\n")
    lines = [f"## {TITLES[name]}", "", f"*Paper:* {CAPTIONS[name]}", ""]
    if name in NOTES:
        lines += [f"*Here:* {NOTES[name]}", ""]
    lines += [f"![{name} {p.stem}]({name}/{p.name})" for p in figures]
    lines += ["", f"Summary: [{name}/summary.txt]({name}/summary.txt)", ""]
    if name == "apophis_2029":
        # --overwrite: a figure run replaces its own outputs (as it does the PNGs above)
        status = encounter([str(CONFIG / f"{name}.yaml"), "--bodies", "1000", "--out",
                            str(out / "encounter"), "--no-arrays", "--overwrite"])
        if status != 0:
            raise SystemExit(f"the encounter ensemble failed ({status})")
        report = out / "encounter" / "summary.txt"   # no wall time in a published summary
        report.write_text("".join(line for line in report.read_text().splitlines(keepends=True)
                                  if not line.startswith("wall time:")))
        lines += [f"![{name} encounter]({name}/encounter/encounter.png)", "",
                  f"Ensemble summary: [{name}/encounter/summary.txt]({name}/encounter/summary.txt)",
                  ""]
        # the same ensemble at the new depth: degree 4, the Moon and the Sun, the Earth's J2
        if apophis_depth(["--out", str(out / "depth")]) != 0:
            raise SystemExit("the Apophis depth run failed")
        lines += [f"![{name} depth]({name}/depth/depth.png)", "",
                  f"At the new depth (degree 4, the Moon, the Sun, the Earth's J2, the degree-3 "
                  f"sensitivity): [{name}/depth/summary.txt]({name}/depth/summary.txt)", ""]
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", type=Path, default=OUT,
                   help=f"output folder (default {OUT.relative_to(ROOT)}/; docs/figures to refresh "
                        "the published figures)")
    p.add_argument("names", nargs="*", metavar="NAME", help=f"figures (default all: {', '.join(CAPTIONS)})")
    args = p.parse_args(argv)
    names = args.names or list(CAPTIONS)
    unknown = [n for n in names if n not in CAPTIONS]
    if unknown:
        print(f"ERROR: unknown figure(s) {unknown}; known: {', '.join(CAPTIONS)}", file=sys.stderr)
        return 1
    out = args.out if args.out.is_absolute() else Path.cwd() / args.out
    sections = {n: make(n, out) for n in names}
    index = out / "README.md"
    existing = {}
    if index.exists():  # keep sections of figures not redone this time
        by_title = {title: name for name, title in TITLES.items()}
        for part in index.read_text().split("\n## ")[1:]:
            key = by_title.get(part.split("\n", 1)[0].strip())
            if key is not None:
                existing[key] = "## " + part.rstrip() + "\n"
    existing.update(sections)
    header = ("# The paper's figures, reproduced, and the Apophis study\n\nMade by `make figures "
              "FIGURES_OUT=docs/figures` (scripts/make_figures.py; plain `make figures` writes "
              "build/figures/) from `tumble_ros/config/fig*.yaml` and `apophis_2029.yaml`: bringup (simulator, comparator with the paper's corrected "
              "analytic solution, recorder), then the offline analysis. Where the analytic model is drawn, "
              "it is the paper's eqs 16–19 with the errata applied (docs/analytic.md).\n\n")
    body = "\n".join(existing[k] for k in CAPTIONS if k in existing)
    index.write_text(header + body)
    print(f"wrote {index}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
