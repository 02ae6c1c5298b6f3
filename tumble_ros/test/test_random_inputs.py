"""
No random state shared between tests: each test draws from a generator of its own.

``make test`` balances the tests over pytest-xdist workers, so the tests a worker runs before a
given one vary from run to run. A generator made once per file (``RNG = default_rng(28)`` at the
top) and drawn from by several tests gives each of them inputs that depend on that order: a
test whose result depends on its input passed alone and failed in some runs (the degree-4 flyby
of ``test_core_multipole.py``). The rule checked here: no test file makes a generator (or seeds
numpy's or Python's global one) outside a function; a test makes its own
(``rng = np.random.default_rng(SEED)``) and hands it to its helpers. An array drawn once at
import for ``parametrize`` (``default_rng(SEED).uniform(...)``) is data, not state, and allowed.
"""
import ast
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent
#: The constructors of random state (numpy's and Python's).
GENERATORS = {'default_rng', 'RandomState', 'Generator', 'Random', 'SystemRandom'}
#: The calls that seed or draw from a global generator (numpy's legacy one, Python's ``random``).
GLOBAL_DRAWS = {('np', 'random'), ('numpy', 'random'), ('random',)}


def _name(node: ast.expr) -> tuple[str, ...]:
    """Return the dotted name of ``node`` as a tuple (``np.random.seed`` -> np, random, seed)."""
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if isinstance(node, ast.Name):
        parts.append(node.id)
        return tuple(reversed(parts))
    return ()


def _shared_fixture(node: ast.AST) -> bool:
    """Tell whether ``node`` is a pytest fixture that outlives one test (scope not 'function')."""
    for decorator in getattr(node, 'decorator_list', []):
        if isinstance(decorator, ast.Call) and _name(decorator.func)[-1:] == ('fixture',):
            for keyword in decorator.keywords:
                if keyword.arg == 'scope' and not (isinstance(keyword.value, ast.Constant)
                                                   and keyword.value.value == 'function'):
                    return True
    return False


def shared_random_state(source: str) -> list[str]:
    """
    Return the places of ``source`` where random state outlives one test.

    A generator built outside any function (module or class level, a default argument) or in a
    fixture of a scope wider than a test, and any call to a global generator (``np.random.seed``,
    ``np.random.normal``, ``random.random``): each as 'line N: what'.
    """
    found = []
    tree = ast.parse(source)
    parents = {id(child): node for node in ast.walk(tree) for child in ast.iter_child_nodes(node)}
    inside = set()                     # the nodes within a function's body, called per test
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            if _shared_fixture(node):
                continue               # a fixture of module or session scope: made once
            body = node.body if isinstance(node.body, list) else [node.body]
            for statement in body:
                inside.update(id(n) for n in ast.walk(statement))
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        name = _name(node.func)
        if name and name[-1] in GENERATORS and id(node) not in inside:
            # a generator made once: allowed only when drawn from on the spot (its value an array)
            parent = parents.get(id(node))
            if not (isinstance(parent, ast.Attribute) and parent.value is node):
                found.append(f'line {node.lineno}: {".".join(name)} outside a test')
        elif name[:-1] in GLOBAL_DRAWS and name[-1] not in GENERATORS | {'SeedSequence'}:
            found.append(f'line {node.lineno}: {".".join(name)} (a global generator)')
    return found


def test_no_test_file_shares_random_state_between_its_tests():
    files = sorted(TESTS.glob('*.py'))
    assert len(files) > 50                                  # the check sees the test files
    found = {f.name: shared_random_state(f.read_text()) for f in files}
    assert {name: places for name, places in found.items() if places} == {}


@pytest.mark.parametrize('source, expected', [
    ('RNG = np.random.default_rng(28)\n', ['line 1: np.random.default_rng outside a test']),
    ('rng = default_rng(3)\n', ['line 1: default_rng outside a test']),
    ('def body(rng=np.random.default_rng(1)):\n    pass\n',
     ['line 1: np.random.default_rng outside a test']),
    ('class T:\n    rng = np.random.RandomState(2)\n',
     ['line 2: np.random.RandomState outside a test']),
    ('np.random.seed(4)\n', ['line 1: np.random.seed (a global generator)']),
    ('def test_x():\n    x = np.random.normal(size=3)\n',
     ['line 2: np.random.normal (a global generator)']),
    ('import random\ndef test_x():\n    random.seed(1)\n',
     ['line 3: random.seed (a global generator)']),
    ("@pytest.fixture(scope='module')\ndef rng():\n    return np.random.default_rng(5)\n",
     ['line 3: np.random.default_rng outside a test']),
    # allowed: a generator of the test's own (or of a fixture per test), an array drawn once at
    # import, a seed sequence
    ('def test_x():\n    rng = np.random.default_rng(28)\n    rng.normal()\n', []),
    ('@pytest.fixture\ndef rng():\n    return np.random.default_rng(5)\n', []),
    ('ANGLES = np.random.default_rng(7).uniform(0, 1, size=(20, 3))\n', []),
    ('def f(seed):\n    return np.random.default_rng(np.random.SeedSequence(seed))\n', []),
])
def test_the_check_sees_every_kind_of_shared_state(source, expected):
    assert shared_random_state(source) == expected
