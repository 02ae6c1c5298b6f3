"""
Every Python block of the user pages (docs/*.md) runs as written, as a script.

Each block is saved as a file in a temporary folder (with ``tumble_ros`` linked into it, so that
the pages' relative paths such as ``tumble_ros/config/fig9.yaml`` resolve and what a block writes
lands there) and run by this interpreter in a fresh process: a block must stand alone, its
imports included (Dask's blocks need their ``__main__`` guard, as a user's script does). The only
change is a smaller size where the page names a long run (OVERRIDES, as the README's test does).

A block that cannot run here says so in the page, on the line just before its fence, with why:
``<!-- doc-test: skip: the reason -->`` (it is then not run); ``<!-- doc-test: continues -->``
runs a block after the page's previous one, in the same script. Any other ``doc-test`` comment
is an error, so a typo cannot skip a block silently.
"""
from __future__ import annotations

from pathlib import Path
import re
import subprocess
import sys
from typing import NamedTuple

import pytest

ROOT = Path(__file__).resolve().parents[2]
#: The user pages; docs/engineering/ and benchmarks/HISTORY.md are engineering notes.
PAGES = sorted((ROOT / 'docs').glob('*.md'))
FENCE = re.compile(r'^```python\n(.*?)^```', re.M | re.S)
MARK = re.compile(r'<!--\s*doc-test:\s*(.*?)\s*-->')
#: Page text -> what the test runs instead: the pages' long runs, shorter.
OVERRIDES = {
    'docs/python.md': {
        'random_impacts(1000,': 'random_impacts(40,',
        'ProgressBar(sc.duration, 1000)': 'ProgressBar(sc.duration, 40)',
        '(1000, 21, 3), True': '(40, 21, 3), True',
        'n_bodies=1_000_000': 'n_bodies=40',
        '"n_bodies": 1000': '"n_bodies": 20',
    },
}


class Block(NamedTuple):
    """A Python block of a page: its first line's number, its code, its doc-test mark."""

    line: int
    code: str
    mark: str


def python_blocks(text: str, name: str = 'page') -> list[Block]:
    """Return a page's Python blocks with the doc-test mark on the line before each fence."""
    blocks = []
    for match in FENCE.finditer(text):
        line = text.count('\n', 0, match.start()) + 1
        before = text[:match.start()].rstrip('\n').rsplit('\n', 1)[-1]
        found = MARK.search(before)
        mark = found.group(1) if found else ''
        if mark and not (mark == 'continues' or re.fullmatch(r'skip: \S.*', mark)):
            raise ValueError(f'{name}:{line - 1}: doc-test mark {mark!r}: expected '
                             "'skip: <why>' or 'continues'")
        blocks.append(Block(line + 1, match.group(1), mark))
    return blocks


def scripts(page: Path) -> list[tuple[str, str]]:
    """Return (id, script) of each block to run: continued ones joined, skipped ones out."""
    name = str(page.relative_to(ROOT))
    out: list[tuple[str, str]] = []
    for block in python_blocks(page.read_text(), name):
        if block.mark.startswith('skip:'):
            continue
        if block.mark == 'continues':
            if not out:
                raise ValueError(f'{name}:{block.line}: continues no block')
            ident, code = out[-1]
            out[-1] = (ident, code + block.code)
        else:
            out.append((f'{name}:{block.line}', block.code))
    overrides = OVERRIDES.get(name, {})
    for text in overrides:
        assert any(text in code for _, code in out), f'{name}: override {text!r} matches nothing'
    return [(ident, _override(code, overrides)) for ident, code in out]


def _override(code: str, overrides: dict[str, str]) -> str:
    for text, replacement in overrides.items():
        code = code.replace(text, replacement)
    return code


ALL = [item for page in PAGES for item in scripts(page)]


def test_the_pages_have_python_to_run():
    assert len(ALL) >= 10, [ident for ident, _ in ALL]


@pytest.mark.parametrize('ident, code', ALL, ids=[ident for ident, _ in ALL])
def test_a_docs_python_block_runs_as_a_script(ident, code, tmp_path):
    (tmp_path / 'tumble_ros').symlink_to(ROOT / 'tumble_ros')
    script = tmp_path / 'block.py'
    script.write_text(code)
    done = subprocess.run([sys.executable, script.name], cwd=tmp_path, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, f'{ident}\n{code}\n{done.stderr[-3000:]}'
    assert 'Traceback' not in done.stderr, f'{ident}\n{done.stderr[-3000:]}'


def test_the_marks_are_read_and_a_wrong_one_is_refused():
    text = ('a\n\n```python\nx = 1\n```\n<!-- doc-test: continues -->\n```python\ny = x\n```\n'
            '<!-- doc-test: skip: needs a ROS graph -->\n```python\nimport rclpy\n```\n')
    blocks = python_blocks(text)
    assert [(b.line, b.code, b.mark) for b in blocks] == [
        (4, 'x = 1\n', ''), (8, 'y = x\n', 'continues'),
        (12, 'import rclpy\n', 'skip: needs a ROS graph')]
    for wrong in ('skip', 'skip:', 'skipped: slow', 'continue'):
        with pytest.raises(ValueError, match='doc-test mark'):
            python_blocks(f'<!-- doc-test: {wrong} -->\n```python\nx = 1\n```\n')
