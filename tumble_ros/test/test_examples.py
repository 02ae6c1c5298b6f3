"""The examples gallery (examples/*.py): each script runs as documented and writes its output."""
from pathlib import Path
import re
import subprocess
import sys

import pytest

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / 'examples'
#: script -> (its arguments after the output folder, the files it must write there)
RUNS = {
    'fig4_against_the_paper.py': ([], ['omega.png', 'error.png']),
    'integrators_on_fig9.py': (None, []),           # prints only; takes no folder
    'ensemble_to_csv.py': (['20'], ['final_omega.csv', 'spread.nc']),
    'apophis_lightcurve.py': ([], ['apophis_lightcurve.png']),
    'coupled_orbit.py': ([], ['coupled_orbit.png']),
}


def test_every_example_is_run_here_and_listed_in_the_gallery():
    scripts = {p.name for p in EXAMPLES.glob('*.py')}
    assert scripts == set(RUNS)
    index = (EXAMPLES / 'README.md').read_text()
    assert all(f'({name})' in index for name in scripts)


def run(script: str, tmp_path: Path) -> subprocess.CompletedProcess:
    extra, _ = RUNS[script]
    args = [] if extra is None else [str(tmp_path / 'out'), *extra]
    done = subprocess.run([sys.executable, str(EXAMPLES / script), *args], cwd=tmp_path,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert 'Traceback' not in done.stderr, done.stderr[-3000:]
    return done


@pytest.mark.parametrize('script', [name for name, (_, files) in RUNS.items() if files])
def test_an_example_writes_its_files(script, tmp_path):
    run(script, tmp_path)
    for name in RUNS[script][1]:
        path = tmp_path / 'out' / name
        assert path.is_file() and path.stat().st_size > 0, name
        if name.endswith('.png'):
            assert path.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n', name
    if script == 'ensemble_to_csv.py':      # one row per body, the header first
        rows = (tmp_path / 'out' / 'final_omega.csv').read_text().splitlines()
        assert rows[0] == 'body,x,y,z' and len(rows) == 21


def test_the_integrators_example_ranks_them_by_their_errors(tmp_path):
    """Errors are deterministic: splitting6 at step 0.004 beats step 0.01 by orders."""
    out = run('integrators_on_fig9.py', tmp_path).stdout
    errors = {m.group(1).strip(): float(m.group(2))
              for m in re.finditer(r'^(.+?)\s+[\d.]+ s .* error ([\d.e+-]+) rad/yr$', out, re.M)}
    assert len(errors) == 4, out
    assert errors['splitting6 step 0.004'] < errors['splitting6 step 0.01'] / 100, errors
