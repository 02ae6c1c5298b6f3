"""
``make figures`` leaves a clone's tracked files as they were (git status unchanged).

It runs the real entry point, ``make figures``, for a reduced figure set (Fig 3 and the Apophis
flyby with its encounter ensemble: the full set takes minutes), through the same recipe and
script as the full run; ``-o setup`` (make's "treat as old") skips the colcon build the test
environment already has.
"""
import hashlib
from pathlib import Path
import shutil
import subprocess

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _git(*args: str) -> str:
    return subprocess.run(['git', *args], cwd=ROOT, check=True, capture_output=True,
                          text=True).stdout


def _state() -> tuple[str, str]:
    """Return the status (tracked changes, untracked files not ignored) and the diff's hash."""
    status = _git('status', '--porcelain=v1', '--untracked-files=all')
    diff = hashlib.sha256(_git('diff', '--binary', 'HEAD').encode()).hexdigest()
    return status, diff


@pytest.mark.skipif(shutil.which('git') is None or shutil.which('make') is None
                    or not (ROOT / '.git').exists(), reason='needs git, make and a git checkout')
def test_make_figures_leaves_git_status_as_it_was():
    before = _state()
    done = subprocess.run(['make', '-o', 'setup', 'figures', 'FIGS=fig3 apophis_2029'],
                          cwd=ROOT, capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-3000:]
    after = _state()
    assert after == before, (before[0], after[0])
    # the figures were made (elsewhere, untracked)
    out = ROOT / 'build' / 'figures'
    assert (out / 'fig3' / 'omega.png').stat().st_size > 0
    assert 'closest approach' in (out / 'apophis_2029' / 'summary.txt').read_text()
    assert 'wall time' not in (out / 'apophis_2029' / 'encounter' / 'summary.txt').read_text()
    assert 'Sensitivity to the degree-3 moments' in (
        out / 'apophis_2029' / 'depth' / 'summary.txt').read_text()
    assert (out / 'apophis_2029' / 'depth' / 'depth.png').stat().st_size > 0
