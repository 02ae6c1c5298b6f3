"""
The docs hold together: every relative link reaches its target.

The pages: README.md, docs/ (the engineering notes included), the benchmarks' history and the
examples' index.

A link reaches a file, and its anchor a heading of that file.
"""
from pathlib import Path
import re

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / 'README.md', *sorted((ROOT / 'docs').glob('*.md')),
         *sorted((ROOT / 'docs' / 'engineering').glob('*.md')), ROOT / 'benchmarks' / 'HISTORY.md',
         ROOT / 'docs' / 'figures' / 'README.md', ROOT / 'examples' / 'README.md']
LINK = re.compile(r'!?\[[^\]]*\]\(([^)\s]+)\)')
#: README lines: the front door stays short (the reference lives in docs/).
README_MAX_LINES = 250


def anchors(path: Path) -> set[str]:
    """Return the GitHub anchors of a Markdown file's headings (lower case, no punctuation)."""
    found = set()
    in_code = False
    for line in path.read_text().splitlines():
        if line.startswith('```'):
            in_code = not in_code
        if in_code or not line.startswith('#'):
            continue
        title = line.lstrip('#').strip().lower()
        found.add(re.sub(r'[^\w\- ]', '', title).replace(' ', '-'))
    return found


def links(path: Path):
    """Yield (line number, target) of each relative link outside code blocks, wrapped or not."""
    prose = []
    in_code = False
    for line in path.read_text().splitlines():
        if line.startswith('```'):
            in_code = not in_code
        prose.append('' if in_code or line.startswith('```') else line)
    text = '\n'.join(prose)
    for match in LINK.finditer(text):
        target = match.group(1)
        if not re.match(r'^[a-z][a-z0-9+.-]*:', target):
            yield text.count('\n', 0, match.start()) + 1, target


@pytest.mark.parametrize('page', PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_relative_link_reaches_its_file_and_heading(page):
    broken = []
    for number, target in links(page):
        name, _, anchor = target.partition('#')
        dest = (page.parent / name).resolve() if name else page
        if not dest.exists():
            broken.append(f'{page.name}:{number}: {target} (no such file)')
        elif anchor and dest.suffix == '.md' and anchor not in anchors(dest):
            broken.append(f'{page.name}:{number}: {target} (no such heading)')
    assert not broken, '\n'.join(broken)


def test_the_readme_is_a_front_door():
    """The README is short, and every docs page is reachable from its table of contents."""
    text = (ROOT / 'README.md').read_text()
    assert len(text.splitlines()) <= README_MAX_LINES
    listed = {Path(target.partition('#')[0]).name for _, target in links(ROOT / 'README.md')}
    missing = [p.name for p in (ROOT / 'docs').glob('*.md') if p.name not in listed]
    assert not missing


def test_a_link_wrapped_over_two_lines_is_checked(tmp_path):
    """A link whose text wraps onto the next line is found, and found on its first line."""
    page = tmp_path / 'page.md'
    page.write_text('# Title\n\nSee [the first\nrun](other.md#a-heading) and [here](#title).\n'
                    '```\n[not a link](nowhere.md)\n```\n')
    assert list(links(page)) == [(3, 'other.md#a-heading'), (4, '#title')]
