"""
A node process imports only what it needs before its node exists (issue 30, node start-up).

Importing a node's module is most of the time from ``ros2 run`` to the node on the graph
(benchmarks/HISTORY.md, "Node start-up"). Each check imports a module in a fresh interpreter
and lists what landed in ``sys.modules``: what no node needs (scipy's integrators, special
functions and optimisers, matplotlib, the analysis, Dask), what only some need (the recorder
runs no numerics: no numba, no ``tumble_ros.core``), and numba's compiled perturber torques,
compiled on first use. No timing is asserted.
"""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

#: Never imported by a node module, nor by ``tumble_ros.core``.
NOT_FOR_NODES = ('scipy.integrate', 'scipy.special', 'scipy.optimize', 'scipy.interpolate',
                 'scipy.spatial', 'scipy.sparse', 'matplotlib', 'tumble_ros.analysis',
                 'tumble_ros.cli', 'tumble_ros.ensembles', 'dask', 'distributed', 'zarr')
#: Not imported by the recorder, which records bytes and runs no numerics.
NOT_FOR_THE_RECORDER = NOT_FOR_NODES + ('numba', 'scipy', 'tumble_ros.core', 'llvmlite')


def imported_after(statement: str) -> list[str]:
    """Return ``sys.modules`` of a fresh interpreter after ``statement`` (this environment)."""
    code = f'import json, sys\n{statement}\nprint(json.dumps(sorted(sys.modules)))'
    out = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                         timeout=120, env=dict(os.environ))
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


def loaded(modules: list[str], packages: tuple[str, ...]) -> list[str]:
    """Return the entries of ``packages`` that are in ``modules``, or one of their submodules."""
    return [p for p in packages if any(m == p or m.startswith(p + '.') for m in modules)]


@pytest.mark.parametrize('node', ['sim', 'comparator', 'recorder', 'bringup'])
def test_a_node_module_imports_no_scipy_solver_no_plotting_no_analysis(node):
    modules = imported_after(f'import tumble_ros.nodes.{node}')
    assert f'tumble_ros.nodes.{node}' in modules     # (the check sees the import)
    assert loaded(modules, NOT_FOR_NODES) == []


def test_the_recorder_imports_no_numerics():
    modules = imported_after('import tumble_ros.nodes.recorder')
    assert loaded(modules, NOT_FOR_THE_RECORDER) == []
    assert 'mcap' in modules      # what it does need is there


def test_the_check_sees_what_a_module_imports():
    # the same check on modules that do import them: it can fail
    modules = imported_after('import tumble_ros.core.integrators.adaptive as a\n'
                             'a._solver_class("DOP853")\n'
                             'import tumble_ros.nodes.sim')
    assert {'scipy.integrate', 'scipy.optimize'} <= set(loaded(modules, NOT_FOR_NODES))
    assert loaded(imported_after('import tumble_ros.core'), ('numba',)) == ['numba']


def test_the_core_compiles_no_perturber_torque_until_one_is_used():
    code = ('import tumble_ros.nodes.sim\n'
            'from tumble_ros.core.torques import perturbers\n'
            'print(json.dumps(perturbers._compiled.cache_info().currsize))')
    out = subprocess.run([sys.executable, '-c', 'import json\n' + code], capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout.strip().splitlines()[-1]) == 0


def test_a_perturbers_compiled_torque_is_its_law():
    from tumble_ros.core.compiling.jit import COMPILED
    from tumble_ros.core.torques.component import SIGNATURE
    from tumble_ros.core.torques.orbits import KeplerOrbit
    from tumble_ros.core.torques.perturbers import (kepler_perturber_torque, Perturber,
                                                    SOURCE_KINDS)

    kind = SOURCE_KINDS[KeplerOrbit]
    assert kind.law is kepler_perturber_torque
    function = kind.function
    assert kind.function is function            # compiled once
    if COMPILED:
        assert function._sig == SIGNATURE
    earth = Perturber('earth', KeplerOrbit(gm=398600.4418, a=4e4, e=0.3, lambda_p=0.4,
                                           inclination=0.2, node=0.1))
    component = earth.torque_component((1.0, 1.6, 2.2))
    assert component.function is function
    par = np.array(component.parameters)
    q = np.array([0.9, 0.1, -0.3, 0.2])
    q = tuple(q / np.linalg.norm(q))
    expected = kepler_perturber_torque(par, 0.37, *q)     # the Python law, interpreted
    np.testing.assert_allclose(function(par, 0.37, *q), expected, rtol=1e-13, atol=0.0)
    assert np.linalg.norm(expected) > 0


def test_the_compiled_dop853_reads_scipys_own_tables():
    from scipy.integrate._ivp import dop853_coefficients as scipy_tables

    from tumble_ros.core.kernels import dop853

    tables = dop853.scipy_tables()
    assert tables is not scipy_tables                # read from the file, not imported
    for name in ('A', 'B', 'C', 'E3', 'E5', 'D'):
        np.testing.assert_array_equal(getattr(tables, name), getattr(scipy_tables, name))
        np.testing.assert_array_equal(getattr(dop853, f'_{name}'), getattr(scipy_tables, name))
    assert (dop853._NSTAGES, dop853._NEXT) == (scipy_tables.N_STAGES,
                                               scipy_tables.N_STAGES_EXTENDED)
