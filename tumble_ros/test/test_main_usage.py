"""``python -m tumble_ros --help`` prints a usage: how to call it, not the module's notes."""
import re
import subprocess
import sys

from tumble_ros.__main__ import EXECUTABLES, main, SUMMARIES
from tumble_ros.core.model.shipped import shipped_scenarios


def test_help_is_a_usage_naming_every_executable(capsys):
    assert main(['--help']) == 0
    out = capsys.readouterr().out
    assert out.startswith('usage: python -m tumble_ros [SCENARIO] [--live]\n'), out
    assert set(SUMMARIES) == set(EXECUTABLES)
    for name in EXECUTABLES:
        assert f'\n  {name} ' in out, name
    assert '--live' in out and 'fig9' in out
    # a usage fits a terminal: no implementation notes (the module docstring has them)
    assert len(out.splitlines()) <= 30, out
    assert 'garbage collector' not in out and ':func:' not in out


def test_help_names_every_shipped_scenario(capsys):
    """SCENARIO may be a shipped scenario's name: the usage lists them (fig4-fig9 as '...')."""
    assert main(['--help']) == 0
    out = capsys.readouterr().out
    for name in shipped_scenarios():
        assert re.search(rf'\b{name}\b', out) or re.fullmatch(r'fig[4-9]', name), name


def test_help_without_docstrings_still_prints_the_usage():
    """``python -OO`` strips the docstrings; the usage is not one."""
    done = subprocess.run([sys.executable, '-OO', '-m', 'tumble_ros', '--help'],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith('usage: python -m tumble_ros'), done.stdout
    assert 'Traceback' not in done.stderr, done.stderr
