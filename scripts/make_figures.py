"""Reproduce the paper's figures: every tumble_ros/config/fig*.yaml -> docs/figures/ (make figures).

For each figure's scenario: run bringup (simulate, compare with the paper's analytic solution,
record to recordings/figures/<fig>.mcap), analyse the recording, write its PNGs to
docs/figures/<fig>/ and its summary to docs/figures/<fig>/summary.txt, and finally the index
docs/figures/README.md that sets each figure beside the paper's caption.

    scripts/env.sh python scripts/make_figures.py [fig3 fig9 ...]   (default: all)
"""
from __future__ import annotations

import sys
from pathlib import Path

from tumble_ros.analysis import analyze, format_summary, load_recording, write_figures
from tumble_ros.analysis.recording import stderr_progress
from tumble_ros.nodes.bringup import format_result, run_bringup

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "tumble_ros" / "config"
OUT = ROOT / "docs" / "figures"
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
}
NOTES = {
    "fig8": "Sampled every 0.02 yr (n = 1000 over 20 yr, as printed).",
    "fig9": "Sampled every 0.01 yr, not the paper's 2 yr (n = 1000 over 2000 yr), which aliases the "
            "~0.07-yr oscillation of ω⊥ (ERRATA.md, last section).",
    "fig10": "The paper prints no parameters for this figure: the Fig 4 body receives a 3·10⁻⁷-yr pulse "
             "about body y at t = 1 yr (config/fig10.yaml). Integrated with the adaptive dop853: the "
             "integration is split at the pulse's edges, so unlike the paper's \"ode\" it does not step "
             "over the pulse (docs/physics.md).",
}


def make(name: str) -> str:
    """Record, analyse and draw one figure; return its section of the index."""
    RECORDINGS.mkdir(parents=True, exist_ok=True)
    recording = RECORDINGS / f"{name}.mcap"
    recording.unlink(missing_ok=True)
    print(f"== {name}", file=sys.stderr)
    result = run_bringup(CONFIG / f"{name}.yaml", output=recording)
    print(format_result(result), file=sys.stderr)
    rec = load_recording(recording, progress=stderr_progress())
    summary = analyze(rec)
    out = OUT / name
    out.mkdir(parents=True, exist_ok=True)
    for old in out.glob("*.png"):
        old.unlink()
    figures = write_figures(rec, out, summary)
    text = format_summary(summary).replace(str(recording), f"recordings/figures/{name}.mcap")
    (out / "summary.txt").write_text(text + "\n")
    lines = [f"## {name.replace('fig', 'Figure ')}", "", f"*Paper:* {CAPTIONS[name]}", ""]
    if name in NOTES:
        lines += [f"*Here:* {NOTES[name]}", ""]
    lines += [f"![{name} {p.stem}]({name}/{p.name})" for p in figures]
    lines += ["", f"Summary: [{name}/summary.txt]({name}/summary.txt)", ""]
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    names = argv or sorted(CAPTIONS, key=lambda n: int(n[3:]))
    unknown = [n for n in names if n not in CAPTIONS]
    if unknown:
        print(f"ERROR: unknown figure(s) {unknown}; known: {', '.join(CAPTIONS)}", file=sys.stderr)
        return 1
    sections = {n: make(n) for n in names}
    index = OUT / "README.md"
    existing = {}
    if index.exists():  # keep sections of figures not redone this time
        for part in index.read_text().split("\n## ")[1:]:
            key = "fig" + part.split("\n", 1)[0].split()[-1]
            existing[key] = "## " + part.rstrip() + "\n"
    existing.update(sections)
    header = ("# The paper's figures, reproduced\n\nMade by `make figures` (scripts/make_figures.py) from "
              "`tumble_ros/config/fig*.yaml`: bringup (simulator, comparator with the paper's corrected "
              "analytic solution, recorder), then the offline analysis. Where the analytic model is drawn, "
              "it is the paper's eqs 16–19 with the errata applied (docs/analytic.md).\n\n")
    body = "\n".join(existing[k] for k in sorted(existing, key=lambda n: int(n[3:])))
    index.write_text(header + body)
    print(f"wrote {index}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
