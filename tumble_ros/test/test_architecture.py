"""
The import map: no circle, and every arrow points down the layers.

Layers, bottom up: ``errors``, ``topics`` and ``file_kinds`` (facts, no imports; file_kinds:
what a path that is not a regular file is, the one table of every reader), ``core`` (numerics,
in rooms of its own: :data:`CORE_ROOMS`), ``io``
(recordings, ensemble stores), ``runs`` (what a run does, without ROS: the ensembles' engines
and runs into io's stores), ``ensembles`` (the run layer's ensemble names, re-exported),
``analysis`` (offline tools over core and io), ``inversion`` (photometry back to a spin
state, over analysis and the ensembles), ``cli`` (command lines over core, runs,
ensembles and analysis; the simulator's parameter names from topics), ``nodes`` (ROS).
``runs`` also holds one run's simulation session, comparison and offline recording (ROS-free
but for the offline writer's serialisation).
A module may import its own package and the layers below, never above.
"""
import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / 'tumble_ros'
#: package -> the tumble_ros packages it may import (besides itself).
ALLOWED = {
    'errors': set(),
    'topics': set(),
    'exits': set(),
    'file_kinds': set(),
    'core': {'errors', 'file_kinds'},
    'io': {'errors', 'topics', 'file_kinds'},
    'runs': {'errors', 'topics', 'file_kinds', 'core', 'io'},
    'ensembles': {'errors', 'file_kinds', 'core', 'io', 'runs'},
    'analysis': {'errors', 'topics', 'file_kinds', 'core', 'io', 'exits'},
    'inversion': {'errors', 'topics', 'file_kinds', 'core', 'io', 'runs', 'ensembles',
                  'analysis', 'exits'},
    'cli': {'errors', 'topics', 'file_kinds', 'core', 'runs', 'ensembles', 'analysis',
            'inversion', 'exits'},
    'nodes': {'errors', 'topics', 'file_kinds', 'core', 'io', 'runs'},
    '__main__': {'nodes', 'analysis', 'inversion', 'cli', 'runs', 'io', 'exits'},
    '__init__': set(),
}


def module_name(path: Path) -> str:
    parts = ('tumble_ros',) + path.relative_to(PACKAGE).with_suffix('').parts
    return '.'.join(parts[:-1] if parts[-1] == '__init__' else parts)


def modules() -> dict[str, Path]:
    return {module_name(p): p for p in PACKAGE.rglob('*.py')}


def imports(path: Path, known: dict[str, Path]) -> set[str]:
    """Return the tumble_ros modules that the file at ``path`` imports, at any depth."""
    this = module_name(path)
    package = this if path.name == '__init__.py' else this.rpartition('.')[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ''
            if node.level:
                anchor = package.split('.')
                anchor = anchor[:len(anchor) - node.level + 1]
                base = '.'.join(anchor + ([base] if base else []))
            # `from pkg import submodule` imports the submodule, else the module itself.
            targets = [f'{base}.{a.name}' if f'{base}.{a.name}' in known else base
                       for a in node.names]
        else:
            continue
        found |= {t for t in targets if t in known and t != this}
    return found


def graph() -> dict[str, set[str]]:
    known = modules()
    return {name: imports(path, known) for name, path in known.items()}


def layer(module: str) -> str:
    return module.split('.')[1] if '.' in module else '__init__'


def test_no_import_circle():
    edges = graph()
    state, stack = {}, []

    def visit(node):
        state[node] = 'open'
        stack.append(node)
        for nxt in sorted(edges[node]):
            if state.get(nxt) == 'open':
                raise AssertionError('import circle: ' + ' -> '.join(
                    stack[stack.index(nxt):] + [nxt]))
            if nxt not in state:
                visit(nxt)
        stack.pop()
        state[node] = 'done'

    for node in sorted(edges):
        if node not in state:
            visit(node)


def test_every_arrow_points_down():
    upward = sorted(f'{a} -> {b}' for a, targets in graph().items() for b in targets
                    if layer(b) != layer(a) and layer(b) not in ALLOWED[layer(a)])
    assert not upward


def external_imports(path: Path) -> set[str]:
    """Return the modules outside tumble_ros that the file at ``path`` imports, at any depth."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and not node.level and node.module:
            found |= {node.module} | {f'{node.module}.{a.name}' for a in node.names}
    return {m for m in found if not m.startswith('tumble_ros.') and m != 'tumble_ros'}


#: ROS in the run layer: only its ROS half (runs.messages: message classes, rclpy's QoS and
#: serialisation) and the offline writer that serialises them; never a node or an executor.
RUNS_ROS_MODULES = ('tumble_ros.runs.messages', 'tumble_ros.runs.offline')
RCLPY_ALLOWED = {'rclpy.serialization', 'rclpy.qos', 'rclpy.duration'}


def _is_ros(target: str) -> bool:
    top = target.split('.')[0]
    return top in {'rclpy', 'rosidl_runtime_py'} or top.endswith(('_msgs', '_interfaces'))


def test_the_run_layer_imports_ros_only_in_its_ros_half():
    ros = []
    for path in sorted((PACKAGE / 'runs').rglob('*.py')):
        name = module_name(path)
        half = any(name == m or name.startswith(m + '.') for m in RUNS_ROS_MODULES)
        for target in sorted(external_imports(path)):
            rclpy_ok = any(target == a or target.startswith(a + '.') for a in RCLPY_ALLOWED)
            if _is_ros(target) and not (half and (target.split('.')[0] != 'rclpy' or rclpy_ok)):
                ros.append(f'{name} -> {target}')
    assert not ros
    builders = PACKAGE / 'runs' / 'messages' / 'builders.py'
    assert 'rclpy.serialization' in external_imports(builders)
    assert 'rclpy.qos' in external_imports(PACKAGE / 'runs' / 'messages' / 'qos.py')


def test_the_run_layer_imports_no_node():
    edges = graph()
    into_nodes = sorted(f'{a} -> {b}' for a, targets in edges.items() for b in targets
                        if layer(a) == 'runs' and layer(b) == 'nodes')
    assert not into_nodes
    assert 'tumble_ros.runs.session' in edges and 'tumble_ros.runs.comparison' in edges
    assert 'tumble_ros.runs.messages.builders' in edges['tumble_ros.runs.offline']


def test_the_check_sees_relative_and_nested_imports():
    known = modules()
    ensemble = imports(PACKAGE / 'core' / 'propagation' / 'ensemble.py', known)
    assert 'tumble_ros.core.kernels' in ensemble  # `from tumble_ros.core import kernels as K`
    assert 'tumble_ros.core.propagation.simulate' in ensemble
    io = imports(PACKAGE / 'io' / '__init__.py', known)
    assert 'tumble_ros.io.columns' in io  # `from .columns import ...`
    assert 'tumble_ros.core' in imports(PACKAGE / 'cli' / 'warmup.py', known)


#: Private attributes of third-party objects that some modules must reach (scipy's solvers,
#: numba's dispatchers and cache, rclpy's node), and the standard library's os._exit (how a
#: forked child ends without the parent's clean-up; the main job's end without the interpreter's
#: teardown, after atexit._run_exitfuncs): (module, expression).
THIRD_PARTY_PRIVATE = {
    ('tumble_ros.exits', 'atexit._run_exitfuncs'),
    ('tumble_ros.exits', 'os._exit'),
    ('tumble_ros.analysis.figure_pool', 'os._exit'),
    ('tumble_ros.core.integrators.adaptive', 'solver._integrator'),
    ('tumble_ros.core.integrators.adaptive', 'solver._y'),
    ('tumble_ros.core.integrators.adaptive', 'ode._integrator'),
    ('tumble_ros.core.integrators.adaptive', 'ode._y'),
    ('tumble_ros.core.compiling.jit', '_IMPL._locator_classes'),
    ('tumble_ros.core.compiling.jit', 'cache_file._load_index'),  # numba's: a loop cached?
    ('tumble_ros.core.torques.component', 'f._sig'),
    ('tumble_ros.nodes.parameters', 'node._parameters'),
    ('tumble_ros.nodes.parameters', 'node._parameter_overrides'),
}


def test_no_module_reaches_into_private_attributes_of_another_object():
    """``x._name`` only on ``self``, ``cls`` or ``super()``: friends use public names."""
    reached = set()
    for name, path in modules().items():
        for node in ast.walk(ast.parse(path.read_text())):
            if not (isinstance(node, ast.Attribute) and node.attr.startswith('_')
                    and not node.attr.startswith('__')):
                continue
            owner = node.value
            if isinstance(owner, ast.Name) and owner.id in ('self', 'cls'):
                continue
            if isinstance(owner, ast.Call) and ast.unparse(owner.func) == 'super':
                continue
            reached.add((name, ast.unparse(node)))
    assert reached <= THIRD_PARTY_PRIVATE, sorted(reached - THIRD_PARTY_PRIVATE)


#: Private names still imported across modules, to be given public names (issue 26: io.columns
#: and io.mcap_reader are another part of that issue's work).
PRIVATE_IMPORTS_LEFT = {('tumble_ros.io.columns', name) for name in (
    '_chunk_records', '_Decoders', '_open', '_Scan', '_SEPARATOR', '_split_sections')}


def test_no_module_imports_a_private_name_of_another():
    imported = set()
    for name, path in modules().items():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and (
                    node.level or (node.module or '').startswith('tumble_ros')):
                imported |= {(name, a.name) for a in node.names
                             if a.name.startswith('_') and not a.name.startswith('__')}
    assert imported <= PRIVATE_IMPORTS_LEFT, sorted(imported - PRIVATE_IMPORTS_LEFT)


#: Core's rooms, bottom up, and the rooms each may import (besides itself): no arrow back up.
#: A room is a subpackage of core or a loose module. ``compiling``: the compile machinery (the
#: numba switch, its adjustments, the cache), apart from the numerics; ``array_types`` and
#: ``units``: facts; ``trig``: plain-arithmetic sin/cos/atan2 the kernels inline; ``torques``;
#: ``kernels``: the physics every path runs and the compiled loops; ``integrators``; ``model``:
#: the body and the validated scenario, whose inputs name the torques and the integrators'
#: settings; ``photometry`` and ``propagation``: what a telescope sees of a scenario's body and
#: its motion in time; ``analytic``: the paper's solution of a scenario; ``__init__``: core's
#: public names.
CORE_ROOMS = {
    'compiling': set(),
    'array_types': set(),
    'units': set(),
    'trig': {'compiling'},
    'torques': {'compiling', 'units', 'trig'},
    'kernels': {'compiling', 'trig', 'torques'},
    'integrators': {'compiling', 'kernels', 'torques'},
    'model': {'compiling', 'array_types', 'units', 'trig', 'torques', 'kernels', 'integrators'},
    'photometry': {'compiling', 'array_types', 'units', 'trig', 'torques', 'model'},
    'propagation': {'compiling', 'array_types', 'units', 'trig', 'torques', 'kernels',
                    'integrators', 'model'},
    'analytic': {'array_types', 'units', 'torques', 'model'},
    '__init__': {'compiling', 'array_types', 'units', 'trig', 'torques', 'kernels',
                 'integrators', 'model', 'photometry', 'propagation', 'analytic'},
}
#: Modules left at an old path when theirs moved (documented import paths keep working): each
#: re-exports the room it moved to, and imports nothing else of core. Those inside a room
#: (``model.units``, ``propagation.timebase``, ``photometry.scattering``...) point down anyway.
CORE_REEXPORTS = {'jit': 'compiling', 'numba_inlining': 'compiling',
                  'numba_blas_check': 'compiling', 'user_cache': 'compiling',
                  'user_files': 'model'}


def core_room(module: str) -> str:
    """Return the room of core that ``module`` (``tumble_ros.core...``) is in."""
    parts = module.split('.')
    return parts[2] if len(parts) > 2 else '__init__'


def core_arrows_back_up(edges: dict[str, set[str]]) -> list[str]:
    """Return every import between core's rooms that :data:`CORE_ROOMS` does not allow."""
    wrong = []
    for module, targets in edges.items():
        if layer(module) != 'core':
            continue
        room = core_room(module)
        allowed = ({CORE_REEXPORTS[room]} if room in CORE_REEXPORTS else CORE_ROOMS[room])
        wrong += [f'{module} -> {target}' for target in sorted(targets)
                  if layer(target) == 'core' and core_room(target) != room
                  and core_room(target) not in allowed]
    return sorted(wrong)


def test_the_rooms_of_core_are_in_order():
    """Each room may import only rooms listed before it (so the table itself has no circle)."""
    order = list(CORE_ROOMS)
    assert [room for k, room in enumerate(order) if not CORE_ROOMS[room] <= set(order[:k])] == []
    assert set(CORE_REEXPORTS.values()) <= set(order) and not set(CORE_REEXPORTS) & set(order)


def test_every_module_of_core_is_in_a_room():
    rooms = {core_room(m) for m in graph() if layer(m) == 'core'}
    assert rooms - set(CORE_ROOMS) - set(CORE_REEXPORTS) == set()
    assert 'compiling' in rooms and 'tumble_ros.core.compiling.jit' in graph()  # (reach)


def test_no_arrow_points_back_up_between_the_rooms_of_core():
    assert core_arrows_back_up(graph()) == []


def test_the_check_of_core_sees_an_arrow_back_up():
    """A made-up import from the torques into the model, and from the machinery into numerics."""
    edges = {'tumble_ros.core.torques.orbits': {'tumble_ros.core.model.limits'},
             'tumble_ros.core.compiling.jit': {'tumble_ros.core.kernels.layout'},
             'tumble_ros.core.jit': {'tumble_ros.core.kernels'},
             'tumble_ros.core.model.scenario': {'tumble_ros.core.torques.orbits'}}
    assert core_arrows_back_up(edges) == [
        'tumble_ros.core.compiling.jit -> tumble_ros.core.kernels.layout',
        'tumble_ros.core.jit -> tumble_ros.core.kernels',
        'tumble_ros.core.torques.orbits -> tumble_ros.core.model.limits']


def test_one_table_says_what_a_path_that_is_no_regular_file_is():
    """Only ``file_kinds`` tests a mode for a FIFO, a device or a socket: the readers ask it."""
    kinds = {'S_ISFIFO', 'S_ISCHR', 'S_ISBLK', 'S_ISSOCK'}
    testing = sorted(name for name, path in modules().items()
                     for node in ast.walk(ast.parse(path.read_text()))
                     if isinstance(node, ast.Attribute) and node.attr in kinds)
    assert testing and set(testing) == {'tumble_ros.file_kinds'}, testing


def private_imports(path: Path) -> list[str]:
    """Return the private names (``_x``) the file at ``path`` imports from other modules."""
    return [f'{node.module}.{a.name}' for node in ast.walk(ast.parse(path.read_text()))
            if isinstance(node, ast.ImportFrom) for a in node.names
            if a.name.startswith('_') and not a.name.startswith('__')]


def test_io_imports_no_private_name_of_another_module():
    found = {name: private_imports(path) for name, path in modules().items()
             if name.startswith('tumble_ros.io')}
    assert not {name: names for name, names in found.items() if names}
