"""
The shipped Foxglove layouts, as the viewer reads them.

Every topic they show is one the nodes publish and every plotted field a number of its type;
every key is one the viewer's panels read (the panel config types of Lichtblick, the
open-source Foxglove Studio, below), titles included; the plots count time as the recordings'
log times do; no legend floats over the data; the 3D panel follows the frame of the markers.
``foxglove_layout.json`` is for every run, ``foxglove_layout_flyby.json`` the same with the
perturber's position (a flyby or a Kepler orbit) in place of the events.
"""
import json
from pathlib import Path

import pytest
from tumble_ros import topics
from tumble_ros.io.msgdefs import message_spec

CONFIG = Path(__file__).resolve().parents[1] / 'config'
LAYOUT = CONFIG / 'foxglove_layout.json'
FLYBY = CONFIG / 'foxglove_layout_flyby.json'
LAYOUTS = [LAYOUT, FLYBY]
NUMERIC = {'float32', 'float64', 'int8', 'uint8', 'int16', 'uint16', 'int32', 'uint32', 'int64',
           'uint64', 'byte'}

# -- what the viewer reads: Lichtblick 1.10.8 (github.com/Lichtblick-Suite/lichtblick, commit
# 9554e1e429c2, 2025-03-21), packages/suite-base/src/ ... -----------------------------------
#: util/layout.ts: PANEL_TITLE_CONFIG_KEY, the key every panel's toolbar shows as its title
#: (components/PanelToolbar/index.tsx); a "title" key is not read (the plots then read "Plot").
TITLE = 'foxglovePanelTitle'
#: context/CurrentLayoutContext/actions.ts: LayoutData.
LAYOUT_KEYS = {'configById', 'layout', 'globalVariables', 'playbackConfig', 'userNodes',
               'savedProps', 'version'}
#: panels/Plot/utils/config.ts: PlotConfig (with DeprecatedPlotConfig) ...
PLOT_KEYS = {'paths', 'minXValue', 'maxXValue', 'minYValue', 'maxYValue', 'showLegend',
             'legendDisplay', 'showPlotValuesInLegend', 'showXAxisLabels', 'showYAxisLabels',
             'isSynced', 'xAxisVal', 'xAxisPath', 'followingViewWidth', 'sidebarDimension',
             'showSidebar', 'sidebarWidth', TITLE}
#: ... PlotPath (BasePlotPath + color, label, timestampMethod, showLine, lineSize) ...
PLOT_PATH_KEYS = {'value', 'enabled', 'color', 'label', 'timestampMethod', 'showLine',
                  'lineSize'}
#: ... PlotXAxisVal, PlotLegendDisplay; util/time.ts: TimestampMethod.
X_AXIS_VALUES = {'timestamp', 'index', 'custom', 'currentCustom'}
LEGEND_DISPLAYS = {'floating', 'top', 'left', 'none'}
TIMESTAMP_METHODS = {'receiveTime', 'headerStamp'}
#: panels/ThreeDeeRender/IRenderer.ts: RendererConfig, its scene, FollowMode; camera.ts:
#: CameraState. RendererConfig.transforms is keyed by frame id (per-frame settings): the
#: "editable" switch belongs to scene.transforms.
RENDERER_KEYS = {'cameraState', 'followTf', 'followMode', 'scene', 'publish', 'transforms',
                 'topics', 'layers', 'imageMode', TITLE}
SCENE_KEYS = {'enableStats', 'backgroundColor', 'labelScaleFactor', 'ignoreColladaUpAxis',
              'meshUpAxis', 'transforms', 'syncCamera', 'topicsVisible'}
SCENE_TRANSFORMS_KEYS = {'editable', 'showLabel', 'labelSize', 'axisScale', 'lineWidth',
                         'lineColor', 'enablePreloading'}
CAMERA_KEYS = {'distance', 'perspective', 'phi', 'target', 'targetOffset', 'targetOrientation',
               'thetaOffset', 'fovy', 'near', 'far'}
FOLLOW_MODES = {'follow-pose', 'follow-position', 'follow-none'}
#: panels/RawMessages/types.ts: RawMessagesPanelConfig.
RAW_KEYS = {'diffEnabled', 'diffMethod', 'diffTopicPath', 'expansion', 'showFullMessageForDiff',
            'topicPath', 'fontSize', TITLE}
#: panels/StateTransitions/types.ts: StateTransitionConfig, StateTransitionPath.
STATES_KEYS = {'isSynced', 'paths', 'xAxisMaxValue', 'xAxisMinValue', 'xAxisRange',
               'showPoints', TITLE}
STATES_PATH_KEYS = {'color', 'value', 'label', 'enabled', 'timestampMethod'}
#: panels/index.ts: the panel types (the part of a panel id before "!").
PANEL_KEYS = {'3D': RENDERER_KEYS, 'Plot': PLOT_KEYS, 'RawMessages': RAW_KEYS,
              'StateTransitions': STATES_KEYS}
PATH_KEYS = {'Plot': PLOT_PATH_KEYS, 'StateTransitions': STATES_PATH_KEYS}


def _layout(path=LAYOUT) -> dict:
    return json.loads(path.read_text())


def _leaves(node) -> list[str]:
    if isinstance(node, str):
        return [node]
    return _leaves(node['first']) + _leaves(node['second'])


def _panels(path, kind: str) -> dict[str, dict]:
    return {name: config for name, config in _layout(path)['configById'].items()
            if name.split('!')[0] == kind}


def _references(path=LAYOUT) -> dict[str, list[str]]:
    """Return {topic: [field paths]} that the layout's panels show."""
    found: dict[str, list[str]] = {}
    for panel, config in _layout(path)['configById'].items():
        kind = panel.split('!')[0]
        if kind == '3D':
            for topic in config['topics']:
                found.setdefault(topic, [])
        elif kind in PATH_KEYS:
            for p in config['paths']:
                topic, _, fields = p['value'].partition('.')
                found.setdefault(topic, []).append(fields)
        elif kind == 'RawMessages':
            found.setdefault(config['topicPath'], [])
        else:
            pytest.fail(f'panel {panel}: a kind this test does not read')
    return found


@pytest.mark.parametrize('path', LAYOUTS, ids=lambda p: p.name)
def test_every_panel_of_the_tree_is_configured_and_every_configured_one_shown(path):
    layout = _layout(path)
    assert sorted(_leaves(layout['layout'])) == sorted(layout['configById'])


def test_every_topic_the_layout_references_is_one_the_nodes_publish(ros):
    from tumble_ros.nodes.comparator import ComparatorNode
    from tumble_ros.nodes.sim import SimNode

    # a Kepler orbit: the simulator publishes perturber too (the flyby layout's)
    ros.start(SimNode, start_paused=True, markers=True, orbit_rate=0.0, **{
        'orbit.kind': 'kepler', 'orbit.gm': 1.3271244e11, 'orbit.a': 1.5e8, 'orbit.e': 0.5})
    ros.start(ComparatorNode)
    referenced = set(_references(LAYOUT)) | set(_references(FLYBY))

    def published():
        return {name: types[0] for name, types in ros.probe.get_topic_names_and_types()}

    assert ros.spin_until(lambda: referenced <= set(published()), 10.0), (
        sorted(referenced - set(published())))
    # the panels the issue asks for: the 3D scene, w with the model, the error, the status,
    # the impacts; the flyby's perturber
    assert {'/' + topics.MARKERS, '/' + topics.ANGULAR_VELOCITY,
            '/' + topics.MODEL_ANGULAR_VELOCITY, '/' + topics.ERROR,
            '/' + topics.COMPARISON_STATUS, '/' + topics.IMPACT_EVENTS} <= set(_references())
    assert '/' + topics.PERTURBER in _references(FLYBY)


@pytest.mark.parametrize('path', LAYOUTS, ids=lambda p: p.name)
def test_every_plotted_field_is_a_number_of_its_topics_type(path):
    for topic, paths in _references(path).items():
        type_name = topics.TYPES[topic.lstrip('/')]
        for field_path in paths:
            spec = message_spec(type_name)
            *parents, leaf = field_path.split('.')
            for name in parents:
                (field,) = [f for f in spec.fields if f.name == name]
                spec = message_spec(field.type.replace('/', '/msg/', 1))
            (field,) = [f for f in spec.fields if f.name == leaf]
            assert field.type in NUMERIC and field.array is None, (topic, field_path)


@pytest.mark.parametrize('path', LAYOUTS, ids=lambda p: p.name)
def test_every_plotted_per_sample_field_is_one_its_description_has(path):
    """The layouts' per-sample topics and fields are those of topics.SAMPLE_TOPICS."""
    described = {'/' + t.name: t for t in topics.SAMPLE_TOPICS}
    shown = {topic: paths for topic, paths in _references(path).items()
             if topic.lstrip('/') in topics.PER_SAMPLE or topic in described}
    assert shown and set(shown) <= set(described), sorted(set(shown) - set(described))
    for topic, paths in shown.items():
        assert set(paths) <= set(described[topic].fields), (topic, paths)


@pytest.mark.parametrize('path', LAYOUTS, ids=lambda p: p.name)
def test_every_key_is_one_the_viewer_reads_and_every_panel_has_a_title(path):
    layout = _layout(path)
    assert set(layout) <= LAYOUT_KEYS and {'configById', 'layout'} <= set(layout)
    for panel, config in layout['configById'].items():
        kind = panel.split('!')[0]
        assert kind in PANEL_KEYS, panel
        assert set(config) <= PANEL_KEYS[kind], (panel, sorted(set(config) - PANEL_KEYS[kind]))
        assert isinstance(config.get(TITLE), str) and config[TITLE], panel
        for p in config.get('paths', []):
            assert set(p) <= PATH_KEYS[kind] and 'value' in p, (panel, p)
            assert p['timestampMethod'] in TIMESTAMP_METHODS, (panel, p)
    titles = [c[TITLE] for c in layout['configById'].values()]
    assert len(set(titles)) == len(titles)


@pytest.mark.parametrize('path', LAYOUTS, ids=lambda p: p.name)
def test_the_plots_count_time_as_the_log_times_and_no_legend_hides_data(path):
    """
    Plot x = a path's time minus the timeline's start (the first log time) [s of ROS time].

    The recordings log each message at the simulated time of its sample (runs/offline.py,
    nodes/recorder.py), so the log time ("receiveTime") is the time base whatever a message
    carries; a header stamp would be off the axis in a recording logged on the wall clock.
    """
    for kind in ('Plot', 'StateTransitions'):
        for panel, config in _panels(path, kind).items():
            assert config['isSynced'] is True, panel
            for p in config['paths']:
                assert p['timestampMethod'] == 'receiveTime', (panel, p['value'])
    for panel, config in _panels(path, 'Plot').items():
        assert config['xAxisVal'] == 'timestamp', panel
        assert config['xAxisVal'] in X_AXIS_VALUES
        assert config['legendDisplay'] in LEGEND_DISPLAYS - {'floating'}, panel


def test_the_impacts_are_on_the_plots_of_w_and_the_events():
    plotted = {p['value']: (name, p) for kind in ('Plot', 'StateTransitions')
               for name, c in _panels(LAYOUT, kind).items() for p in c['paths']}
    for axis in 'xyz':
        name, p = plotted[f'/{topics.IMPACT_EVENTS}.delta_omega.{axis}']
        assert name == f'Plot!w{axis}'
        assert p['showLine'] is False and p['lineSize'] >= 3   # one point an impact: visible
    assert plotted[f'/{topics.IMPACT_EVENTS}.id'][0].startswith('StateTransitions!')


def test_the_flyby_layout_is_the_default_with_the_perturber_for_the_events():
    default, flyby = _layout(LAYOUT), _layout(FLYBY)
    only_default = set(default['configById']) - set(flyby['configById'])
    only_flyby = set(flyby['configById']) - set(default['configById'])
    assert only_default == {'StateTransitions!events'} and only_flyby == {'Plot!perturber'}
    for name in set(default['configById']) & set(flyby['configById']) - {'3D!tumble'}:
        assert flyby['configById'][name] == default['configById'][name], name
    values = [p['value'] for p in flyby['configById']['Plot!perturber']['paths']]
    assert values == [f'/{topics.PERTURBER}.vector.{a}' for a in 'xyz']


@pytest.mark.parametrize('path', LAYOUTS, ids=lambda p: p.name)
def test_the_3d_panel_follows_the_frame_of_the_markers(path):
    (panel,) = _panels(path, '3D').values()
    assert panel['followTf'] == topics.FRAME_ORBITAL
    assert panel['followMode'] in FOLLOW_MODES - {'follow-none'}
    # the scene's moving part and its shape (sent once, posed by TF: test_tf.py)
    assert list(panel['topics']) == ['/' + topics.MARKERS, '/' + topics.BODY_MARKERS]
    assert all(panel['topics'][t]['visible'] is True for t in panel['topics'])
    assert set(panel['scene']) <= SCENE_KEYS
    assert set(panel['scene'].get('transforms', {})) <= SCENE_TRANSFORMS_KEYS
    assert set(panel['cameraState']) <= CAMERA_KEYS
    # per-frame settings: only frames the recording has
    assert set(panel['transforms']) <= {topics.FRAME_ORBITAL}
