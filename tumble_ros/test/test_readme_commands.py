"""
The README's commands run as written, in a clean clone, and leave it clean.

The test clones the repository (its committed HEAD) into a temporary folder, lends the clone this
checkout's set-up (the venv and colcon's install/: `make setup` is what `make test` already ran
here, so the clone's `make` is told it is done with `-o setup`), and runs every command of the
README's "Ways in" that needs no `ros2` command line, with the shorter sizes the README allows
(fewer bodies, a shorter duration), then checks that each succeeded, wrote what the README says,
The `ros2 run` / `ros2 launch` lines need a
real ROS 2 install and are not run here; the `pip install` lines would install into this venv
(test_packaging.py builds and installs the package into a venv of its own instead).
"""
from __future__ import annotations

from pathlib import Path
import re
import shlex
import subprocess

import pytest

ROOT = Path(__file__).resolve().parents[2]
README = (ROOT / 'README.md').read_text()
#: README text -> what the test runs instead: smaller sizes, and the newcomer's edit done by sed.
OVERRIDES = {
    '$EDITOR my.yaml': "sed -i 's/duration: 2.0 /duration: 0.2 /' my.yaml",
    '--bodies 1000 ': '--bodies 20 ',
    '--bodies 10000 ': '--bodies 40 ',
    'n_bodies=10_000': 'n_bodies=40',
}


def blocks(language: str) -> list[str]:
    """Return the README's fenced code blocks of one language, in order."""
    return re.findall(rf'^```{language}\n(.*?)^```', README, re.M | re.S)


def shell_commands() -> list[str]:
    """Return the README's bash commands that need no ros2 CLI, joined and overridden."""
    commands = []
    for block in blocks('bash')[1:]:            # the first block is `make run` / `make test`
        joined = re.sub(r'\\\n\s*', ' ', block)
        for line in joined.splitlines():
            line = line.split('  #', 1)[0].strip()
            # not ros2 (no ros2 CLI here), nor pip install (it would install into the test's
            # venv: test_packaging.py builds and installs the package into a venv of its own)
            if not line or line.startswith(('ros2 ', 'pip ')):
                continue
            for text, replacement in OVERRIDES.items():
                line = line.replace(text, replacement)
            commands.append(line)
    return commands


def python_blocks() -> list[str]:
    out = []
    for block in blocks('python'):
        for text, replacement in OVERRIDES.items():
            block = block.replace(text, replacement)
        out.append(block)
    return out


@pytest.fixture(scope='module')
def clone(tmp_path_factory):
    path = tmp_path_factory.mktemp('readme') / 'tumble_ros'
    subprocess.run(['git', 'clone', '-q', str(ROOT), str(path)], check=True)
    for lent in ('.venv', 'install', 'build'):
        (path / lent).symlink_to(ROOT / lent)
    return path


def run(clone: Path, command: str, timeout: float = 300.0) -> subprocess.CompletedProcess:
    return subprocess.run(['bash', '-c', command], cwd=clone, capture_output=True, text=True,
                          timeout=timeout)


def test_the_readme_shows_commands_to_run():
    commands = shell_commands()
    assert any(c.startswith('make run CONFIG=my.yaml') for c in commands), commands
    assert any('encounter' in c for c in commands) and any('ensemble' in c for c in commands)
    assert len(python_blocks()) >= 2


def test_the_readme_commands_run_in_a_clean_clone(clone):
    for command in shell_commands():
        command = command.replace('make run', 'make -o setup run', 1)
        done = run(clone, command)
        assert done.returncode == 0, f'{command}\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}'
        assert 'Traceback' not in done.stderr, command
    figures = list((clone / 'recordings').glob('my_*_figures/omega.png'))
    assert figures, sorted(p.name for p in (clone / 'recordings').iterdir())


@pytest.mark.parametrize('index', range(2), ids=['python-api', 'dask'])
def test_the_readme_python_runs_as_a_script(clone, index):
    """Each Python block, saved as a file and run as a script (Dask needs its __main__ guard)."""
    script = clone / f'readme_{index}.py'
    script.write_text(python_blocks()[index])
    done = run(clone, f'scripts/env.sh python {shlex.quote(script.name)}')
    script.unlink()
    assert done.returncode == 0, done.stderr[-3000:]
    assert 'Traceback' not in done.stderr
