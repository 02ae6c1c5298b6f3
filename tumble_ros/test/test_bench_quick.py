"""``make bench BENCH_ARGS=--quick`` judges nothing against the full run's targets."""
import io
from pathlib import Path
import sys

import pytest

BENCH = Path(__file__).resolve().parents[2] / 'benchmarks'


@pytest.fixture()
def bench(monkeypatch):
    monkeypatch.syspath_prepend(str(BENCH))
    import common
    import issue12_summary
    yield common, issue12_summary
    for name in ('common', 'issue12_summary'):
        sys.modules.pop(name, None)


def _far_from_the_targets(summary) -> dict:
    """Return section results of a small run: every figure far from its target."""
    return {summary.MAIN_JOB: {'wall_s': [40.0]}, summary.READING: {'columnar_per_s': 2e4},
            summary.STANDALONE: {'events': {'samples_per_s': 900.0, 'lost': {}}},
            summary.ENSEMBLE: {'splitting N=10000': {'body_steps_per_s': 1e6}}}


@pytest.mark.parametrize('quick', [True, False])
def test_a_quick_run_gives_no_verdict_the_full_run_does(bench, quick):
    common, summary = bench
    out = io.StringIO()
    ctx = common.Context(quick=quick, out=out, results=_far_from_the_targets(summary))
    summary.issue12_section(ctx)
    text = out.getvalue()
    if quick:
        assert 'MISSED' not in text and 'MET' not in text, text
        assert 'no verdict' in text
        assert ctx.verdict(False) == ctx.verdict(True) != 'MET'
    else:
        assert text.count('MISSED') == 4, text
        assert ctx.verdict(True) == 'MET' and ctx.verdict(False, 'MISSED by 2x') == 'MISSED by 2x'
