"""Scenario validation, parameter round trips and YAML loading."""
import math
from pathlib import Path
import pickle
import re

import numpy as np
import pytest

from tumble_ros.core import (Impact, IntegratorSettings, load_scenario, Scenario, ScenarioError,
                             simulate)

CONFIG = Path(__file__).resolve().parents[1] / 'config'

BAD_FIELDS = [
    ({'inertia': (1.0, 1.0)}, 'inertia'),
    ({'inertia': (1.0, -1.0, 1.5)}, 'inertia[1]'),
    ({'inertia': (1.0, 1.0, math.nan)}, 'inertia[2]'),
    ({'inertia': (1.0, 1.0, 4.0)}, 'inertia'),  # a = 3: not realisable
    ({'allow_unphysical_inertia': 'yes'}, 'allow_unphysical_inertia'),
    ({'orbit_rate': -1.0}, 'orbit_rate'),
    ({'orbit_rate': math.inf}, 'orbit_rate'),
    ({'omega0': (0.0, 'x', 1.0)}, 'omega0[1]'),
    ({'euler0': (0.5, 0.0)}, 'euler0'),
    ({'euler0': (0.5, 0.0, 0.0), 'attitude': 'euler'}, 'euler0[2]'),
    ({'euler0': (0.5, 0.0, math.pi), 'attitude': 'euler'}, 'euler0[2]'),
    ({'attitude': 'matrix'}, 'attitude'),
    ({'duration': 0.0}, 'duration'),
    ({'output_interval': -0.1}, 'output_interval'),
    ({'output_interval': 5.0}, 'output_interval'),
    ({'impacts': (Impact(1.9, 0.2, (1.0, 0.0, 0.0)),)}, 'impacts[0].start'),
]


@pytest.mark.parametrize('changes,field', BAD_FIELDS)
def test_invalid_field_is_rejected_naming_it(changes, field):
    with pytest.raises(ScenarioError) as err:
        Scenario(**changes)
    assert str(err.value).startswith(field + ':'), str(err.value)


BAD_INTEGRATOR = [
    ({'method': 'euler'}, 'integrator.method'),
    ({'rtol': 0.5}, 'integrator.rtol'),
    ({'rtol': 1e-16}, 'integrator.rtol'),
    ({'atol': 0.0}, 'integrator.atol'),
    ({'step': -1e-3}, 'integrator.step'),
    ({'max_step': -1.0}, 'integrator.max_step'),
]


@pytest.mark.parametrize('changes,field', BAD_INTEGRATOR)
def test_invalid_integrator_setting_is_rejected_naming_it(changes, field):
    with pytest.raises(ScenarioError, match=f'^{re.escape(field)}:'):
        IntegratorSettings(**changes)


@pytest.mark.parametrize('changes,field', [
    ({'start': -1.0}, 'impact.start'),
    ({'duration': 0.0}, 'impact.duration'),
    ({'torque': (1.0, math.nan, 0.0)}, 'impact.torque[1]'),
    ({'frame': 'world'}, 'impact.frame'),
])
def test_invalid_impact_is_rejected_naming_it(changes, field):
    fields = {'start': 0.1, 'duration': 3e-7, 'torque': (1.0, 0.0, 0.0), 'frame': 'body'} | changes
    with pytest.raises(ScenarioError, match=f'^{re.escape(field)}'):
        Impact(**fields)


def test_an_impact_is_held_as_floats_and_a_tuple_whatever_numbers_it_is_given():
    given = Impact(np.float32(0.5), 1, [np.int64(2), 0.25, np.float64(-3.0)], 'orbital')
    assert (given.start, given.duration, given.torque) == (0.5, 1.0, (2.0, 0.25, -3.0))
    assert all(type(v) is float for v in (given.start, given.duration, *given.torque))
    # fields already so pass unchanged; the scenario checks each impact again
    same = Impact(0.5, 1.0, (2.0, 0.25, -3.0), 'orbital')
    assert same == given and Scenario(duration=2.0, impacts=(given,)).impacts == (same,)
    for bad, field in [({'start': True}, 'impact.start'), ({'duration': 1e-30}, 'impact.duration'),
                       ({'torque': (1.0, 2.0)}, 'impact.torque'),
                       ({'torque': (1.0, 2.0, math.inf)}, 'impact.torque[2]')]:
        fields = {'start': 0.5, 'duration': 1.0, 'torque': (2.0, 0.25, -3.0)} | bad
        with pytest.raises(ScenarioError, match=f'^{re.escape(field)}'):
            Impact(**fields)
    # a scenario and its impacts as Dask ships them to workers
    sc = Scenario(duration=2.0, impacts=(given, Impact(1.0, 3e-7, (0.0, 1.0, 0.0))))
    assert pickle.loads(pickle.dumps(sc)) == sc


def test_unphysical_inertia_allowed_on_request():
    sc = Scenario(inertia=(1.0, 1.0, 4.0), allow_unphysical_inertia=True)
    assert sc.inertia == (1.0, 1.0, 4.0)


def test_parameters_round_trip():
    sc = Scenario(inertia=(1.0, 1.2, 1.5), impacts=(Impact(0.5, 3e-7, (1.0, 2.0, 3.0), 'orbital'),
                                                    Impact(1.0, 1e-6, (0.0, 0.0, 5.0))),
                  integrator=IntegratorSettings(method='rk4', step=1e-3))
    params = sc.to_parameters()
    assert params['impacts.torque'] == [1.0, 2.0, 3.0, 0.0, 0.0, 5.0]
    assert Scenario.from_parameters(params) == sc


@pytest.mark.parametrize('params,field', [
    ({'inertai': [1, 1, 1]}, 'inertai'),
    ({'impacts.start': [0.1], 'impacts.duration': [], 'impacts.torque': [1, 0, 0]},
     'impacts.duration'),
    ({'impacts.start': [0.1], 'impacts.duration': [1e-7], 'impacts.torque': [1, 0]},
     'impacts.torque'),
    ({'impacts.start': [0.1], 'impacts.duration': [-1e-7], 'impacts.torque': [1, 0, 0]},
     'impacts[0].duration'),
    ({'integrator.rtol': 2.0}, 'integrator.rtol'),
])
def test_bad_parameters_name_the_parameter(params, field):
    with pytest.raises(ScenarioError, match=f'^{re.escape(field)}'):
        Scenario.from_parameters(params)


def test_load_scenario_from_ros_params_yaml(tmp_path):
    path = tmp_path / 's.yaml'
    path.write_text(
        'sim:\n  ros__parameters:\n    inertia: [1.0, 1.0, 1.5]\n    euler0: [0.5, 0.0, 0.5]\n'
        '    integrator:\n      method: rk45\n      rtol: 1.0e-9\n'
        '    impacts:\n      start: [0.5]\n      duration: [3.0e-7]\n'
        '      torque: [0.0, 0.0, 1.0e6]\n'
        '    real_time_factor: 0.0\n'
    )
    sc = load_scenario(path, ignore=frozenset({'real_time_factor'}))
    assert sc.integrator.method == 'rk45' and sc.integrator.rtol == 1e-9
    assert sc.impacts == (Impact(0.5, 3e-7, (0.0, 0.0, 1e6)),)
    with pytest.raises(ScenarioError, match='real_time_factor'):
        load_scenario(path)


@pytest.mark.parametrize('text,why', [
    ('', 'expected a ROS 2 parameters file'),
    ('sim: [1, 2]', 'ros__parameters'),
    ('a: {ros__parameters: {}}\nb: {ros__parameters: {}}', 'no section'),
    ('sim:\n  ros__parameters:\n    duration: -1\n', 'duration'),
    ('sim: {ros__parameters: {inertia: [1, 1}}', 'not valid YAML'),
])
def test_load_scenario_errors(tmp_path, text, why):
    path = tmp_path / 'bad.yaml'
    path.write_text(text)
    with pytest.raises(ScenarioError, match=why):
        load_scenario(path)


def test_config_files_load_and_run_briefly():
    files = sorted(CONFIG.glob('*.yaml'))
    assert {f.name for f in files} >= {'default.yaml'} | {f'fig{k}.yaml' for k in range(3, 11)}
    for f in files:
        sc = load_scenario(f)
        r = simulate(sc, t_eval=np.linspace(0, min(sc.duration, 0.01), 3))
        assert r.success, (f, r.message)


def test_default_yaml_is_the_default_scenario():
    assert load_scenario(CONFIG / 'default.yaml') == Scenario()


def test_simulate_rejects_bad_t_eval():
    for bad in ([], [0.2, 0.1], [0.0, 3.0], [math.nan]):
        with pytest.raises(ScenarioError, match='t_eval'):
            simulate(Scenario(), t_eval=bad)


def test_every_parameter_is_documented():
    from tumble_ros.core.model.scenario import PARAMETER_DOCS, PARAMETER_NAMES

    assert set(PARAMETER_DOCS) == set(PARAMETER_NAMES) == set(Scenario().to_parameters())


@pytest.mark.parametrize('impact,now,field', [
    (Impact(0.5, 2e-3, (1.0, 0.0, 0.0)), 0.0, 'duration'),
    (Impact(0.5, 1e-6, (1e10, 0.0, 0.0)), 0.0, 'torque'),
    (Impact(0.5, 1e-6, (1.0, 0.0, 0.0)), 0.6, 'start'),
    (Impact(1.9999999, 1e-6, (1.0, 0.0, 0.0)), 0.0, 'start'),
])
def test_impact_limits_refuse_with_the_field_named(impact, now, field):
    from tumble_ros.core import ImpactLimits

    with pytest.raises(ScenarioError, match=f'^{field}:'):
        ImpactLimits(max_duration=1e-3, max_impulse=100.0).check(impact, now=now, end=2.0)
    ImpactLimits().check(Impact(0.7, 1e-6, (1.0, 0.0, 0.0)), now=0.6, end=2.0)  # a good one passes


def test_dump_parse_round_trip():
    from tumble_ros.core import dump_scenario, parse_scenario

    sc = Scenario(impacts=(Impact(0.5, 3e-7, (1.0, 2.0, 3.0), 'orbital'),), attitude='euler')
    assert parse_scenario(dump_scenario(sc)) == sc


def test_the_impacts_lists_are_written_as_pyyaml_writes_them():
    """
    dump_scenario writes the impacts' lists itself (PyYAML's representer: 0.45 s at 10,000).

    The text must be PyYAML's own, character for character, for floats of every spelling
    (exponents with and without a decimal point, -0.0, huge and tiny) and both frames.
    """
    import yaml

    from tumble_ros.core import dump_scenario, parse_scenario

    rng = np.random.default_rng(5)
    torques = [(0.0, -0.0, 1e17), (1e-300, 123456789.0, -2.5e-07), (1e16, 1e22, 5e-324)]
    impacts = tuple(Impact(float(s), float(d), torques[k % 3], ('body', 'orbital')[k % 2])
                    for k, (s, d) in enumerate(zip(np.sort(rng.uniform(0.0, 1.0, 200)),
                                                   10.0 ** rng.uniform(-9, -3, 200))))
    sc = Scenario(duration=2.0, impacts=impacts)
    pyyaml = yaml.dump({'/**/sim': {'ros__parameters': sc.to_parameters()}},
                       Dumper=yaml.SafeDumper, sort_keys=False)
    assert dump_scenario(sc) == pyyaml
    assert parse_scenario(dump_scenario(sc)) == sc
    assert dump_scenario(sc.replace(impacts=())) == yaml.dump(
        {'/**/sim': {'ros__parameters': sc.replace(impacts=()).to_parameters()}},
        Dumper=yaml.SafeDumper, sort_keys=False)


def test_a_params_file_over_the_size_limit_is_refused_before_it_is_read(tmp_path):
    """A 60-MB omega0 list was parsed (1.2 GB held); now its size alone refuses it."""
    from tumble_ros.core.model.limits import MAX_PARAMS_FILE_BYTES

    path = tmp_path / 'huge.yaml'
    head = 'sim:\n  ros__parameters:\n    omega0: ['
    path.write_text(head + '1.0, ' * ((MAX_PARAMS_FILE_BYTES - len(head)) // 5 + 1) + '1.0]\n')
    with pytest.raises(ScenarioError) as err:
        load_scenario(path)
    assert str(err.value) == (f'params file {path}: {path.stat().st_size:,} bytes, above the '
                              f'limit of {MAX_PARAMS_FILE_BYTES:,} (MAX_PARAMS_FILE_BYTES, '
                              'docs/ros.md "Limits of the inputs")')


def test_a_long_wrong_list_is_named_in_a_short_line(tmp_path):
    path = tmp_path / 'long.yaml'
    path.write_text('sim:\n  ros__parameters:\n    omega0: [' + ', '.join(['1.0'] * 50_000)
                    + ']\n')
    with pytest.raises(ScenarioError) as err:
        load_scenario(path)
    assert str(err.value).startswith(f'{path}: omega0: ')
    assert 'list of 50,000 entries [1.0, 1.0, 1.0, ...]' in str(err.value)
    assert len(str(err.value)) < 300


def test_more_scheduled_impacts_than_the_limit_are_refused_before_the_run():
    """10**6 scheduled impacts took 3.9 GB and produced nothing."""
    from tumble_ros.core.model.limits import MAX_IMPACTS

    n = MAX_IMPACTS + 1
    params = {'duration': 2.0, 'impacts.start': [1.0 * k / n for k in range(n)],
              'impacts.duration': [1e-7] * n, 'impacts.torque': [0.0, 0.0, 1.0] * n}
    with pytest.raises(ScenarioError, match=f'impacts.start: at most {MAX_IMPACTS:,} scheduled '
                                            'impacts per run') as err:
        Scenario.from_parameters(params)
    assert len(str(err.value)) < 300
    impacts = tuple(Impact(1.0 * k / n, 1e-7, (0.0, 0.0, 1.0)) for k in range(n))
    with pytest.raises(ScenarioError, match=f'impacts: at most {MAX_IMPACTS:,}'):
        Scenario(duration=2.0, impacts=impacts)
    assert len(Scenario(duration=2.0, impacts=impacts[:MAX_IMPACTS]).impacts) == MAX_IMPACTS
