"""
The shipped Foxglove layouts, as the viewer reads them.

Every topic they show is one the nodes publish and every plotted field a number of its type;
every key is one the viewer's panels read (the panel config types of Lichtblick, the
open-source Foxglove Studio, below), titles included; the plots count time as the recordings'
log times do; no legend floats over the data; the 3D panel follows the frame of the markers.
One layout per timeline unit (``analysis.viewer_layouts``, which the main job names for the
recording): ``foxglove_layout.json`` for the runs in years, ``foxglove_layout_flyby.json`` for
the runs in hours (the flyby: the Earth's position in place of the Sun's label, its rates
converted to rad/h by user scripts). Every plot states its units; the comparator's series are
dots (it publishes nothing where its model does not apply); every panel has room at 1280x800.
"""
import json
from pathlib import Path
import re

import pytest
from tumble_ros import topics
from tumble_ros.analysis.viewer_layouts import layout_for, layout_line, LAYOUTS as VIEWER_LAYOUTS
from tumble_ros.core.model.scenario import load_scenario
from tumble_ros.core.units import HOURS_PER_YEAR, seconds_per_year_of
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
#: types/layouts.ts: TabPanelConfig, TabConfig (a tab's title and its layout tree).
TAB_KEYS = {'activeTabIdx', 'tabs'}
TAB_ITEM_KEYS = {'title', 'layout'}
#: types/panels.ts: UserScript; players/UserScriptPlayer: a script's output topics start with
#: util/globalConstants.ts DEFAULT_STUDIO_SCRIPT_PREFIX.
SCRIPT_KEYS = {'name', 'sourceCode'}
SCRIPT_PREFIX = '/studio_script/'
#: panels/index.ts: the panel types (the part of a panel id before "!").
PANEL_KEYS = {'3D': RENDERER_KEYS, 'Plot': PLOT_KEYS, 'RawMessages': RAW_KEYS,
              'StateTransitions': STATES_KEYS, 'Tab': TAB_KEYS}
PATH_KEYS = {'Plot': PLOT_PATH_KEYS, 'StateTransitions': STATES_PATH_KEYS}


def _layout(path=LAYOUT) -> dict:
    return json.loads(path.read_text())


def _leaves(node, config: dict | None = None) -> list[str]:
    """Return the panels of a layout tree, with those of its Tab panels' tabs (``config``)."""
    if node is None:
        return []
    if isinstance(node, str):
        tabs = (config or {}).get(node, {}).get('tabs', []) if node.startswith('Tab!') else []
        return [node] + [leaf for tab in tabs for leaf in _leaves(tab.get('layout'), config)]
    return _leaves(node['first'], config) + _leaves(node['second'], config)


def _scripts(path) -> dict[str, tuple[str, str, str]]:
    """Return {output topic: (input topic, Output type's text, source)} of the user scripts."""
    found = {}
    for name, script in _layout(path).get('userNodes', {}).items():
        assert set(script) == SCRIPT_KEYS, name
        source = script['sourceCode']
        (inputs,) = re.findall(r'export const inputs = \[(.*)\];', source)
        (output,) = re.findall(r'export const output = "(.*)";', source)
        (output_type,) = re.findall(r'type Output = \{(.*)\};', source)
        (source_topic,) = json.loads(f'[{inputs}]')
        found[output] = (source_topic, output_type, source)
    return found


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
        elif kind == 'Tab':
            continue
        else:
            pytest.fail(f'panel {panel}: a kind this test does not read')
    return found


@pytest.mark.parametrize('path', LAYOUTS, ids=lambda p: p.name)
def test_every_panel_of_the_tree_is_configured_and_every_configured_one_shown(path):
    layout = _layout(path)
    assert sorted(_leaves(layout['layout'], layout['configById'])) == sorted(layout['configById'])


def test_every_topic_the_layout_references_is_one_the_nodes_publish(ros):
    from tumble_ros.nodes.comparator import ComparatorNode
    from tumble_ros.nodes.sim import SimNode

    # a Kepler orbit: the simulator publishes perturber too (the flyby layout's)
    ros.start(SimNode, start_paused=True, markers=True, orbit_rate=0.0, **{
        'orbit.kind': 'kepler', 'orbit.gm': 1.3271244e11, 'orbit.a': 1.5e8, 'orbit.e': 0.5})
    ros.start(ComparatorNode)
    referenced = {topic for path in LAYOUTS for topic in _references(path)
                  if not topic.startswith(SCRIPT_PREFIX)}
    referenced |= {source for path in LAYOUTS for source, _, _ in _scripts(path).values()}

    def published():
        return {name: types[0] for name, types in ros.probe.get_topic_names_and_types()}

    assert ros.spin_until(lambda: referenced <= set(published()), 10.0), (
        sorted(referenced - set(published())))
    # the panels the issue asks for: the 3D scene, w with the model, the error, the status,
    # the impacts; the flyby's perturber
    assert {'/' + topics.MARKERS, '/' + topics.ANGULAR_VELOCITY,
            '/' + topics.MODEL_ANGULAR_VELOCITY, '/' + topics.ERROR,
            '/' + topics.COMPARISON_STATUS, '/' + topics.IMPACT_EVENTS} <= set(_references())
    assert '/' + topics.PERTURBER in {source for source, _, _ in _scripts(FLYBY).values()}


@pytest.mark.parametrize('path', LAYOUTS, ids=lambda p: p.name)
def test_every_plotted_field_is_a_number_of_its_topics_type(path):
    scripts = _scripts(path)
    for topic, paths in _references(path).items():
        if topic.startswith(SCRIPT_PREFIX):     # a user script's output: a field of its Output
            fields = re.findall(r'(\w+): number', scripts[topic][1])
            assert paths and set(paths) <= set(fields), (topic, paths, fields)
            continue
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
        if kind == 'Tab':       # no toolbar: each tab's title names what it holds
            assert all(set(tab) <= TAB_ITEM_KEYS and tab['title'] for tab in config['tabs'])
            assert 0 <= config['activeTabIdx'] < len(config['tabs'])
            continue
        assert isinstance(config.get(TITLE), str) and config[TITLE], panel
        for p in config.get('paths', []):
            assert set(p) <= PATH_KEYS[kind] and 'value' in p, (panel, p)
            assert p['timestampMethod'] in TIMESTAMP_METHODS, (panel, p)
    titles = [c[TITLE] for c in layout['configById'].values() if TITLE in c]
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


def test_the_flyby_layout_is_the_default_with_the_earth_and_its_rates_in_hours():
    """The same panels, series, labels and colours; rates through the scripts; the Earth."""
    default, flyby = _layout(LAYOUT)['configById'], _layout(FLYBY)['configById']
    assert set(flyby) - set(default) == {'Plot!perturber'} and set(default) <= set(flyby)
    scripts = _scripts(FLYBY)
    for name in set(default) - {'3D!tumble', 'Tab!more'}:
        ours, theirs = default[name].get('paths', []), flyby[name].get('paths', [])
        assert len(ours) == len(theirs), name
        for mine, its in zip(ours, theirs):
            assert {k: v for k, v in mine.items() if k != 'value'} == (
                {k: v for k, v in its.items() if k != 'value'}), (name, mine)
            topic = its['value'].split('.')[0]
            if topic in scripts:     # the script reads the default's topic and field
                source, _, code = scripts[topic]
                assert mine['value'].startswith(source + '.'), (name, mine['value'])
                parent, _, leaf = mine['value'][len(source) + 1:].rpartition('.')
                assert its['value'] == f'{topic}.{leaf}', (name, its['value'])
                assert f'event.message.{parent or leaf}' in code, (name, mine['value'])
            else:
                assert its['value'] == mine['value'], name
    # the Earth, never "the Sun"; its position in body axes plotted, as a tab beside the events
    titles = [c.get(TITLE, '') for c in flyby.values()]
    assert not [t for t in titles if 'the Sun' in t] and 'the Earth' in flyby['3D!tumble'][TITLE]
    perturber = {scripts[p['value'].split('.')[0]][0]
                 for p in flyby['Plot!perturber']['paths']}
    assert perturber == {'/' + topics.PERTURBER}
    assert {'title': 'the Earth', 'layout': 'Plot!perturber'} in flyby['Tab!more']['tabs']


#: The panels whose values are rates [rad per time unit]: w, the model, the impacts, the error.
RATE_PANELS = {'Plot!wx', 'Plot!wy', 'Plot!wz', 'Plot!error'}
_UNIT = re.compile(r'\[([^\]]+)\]')


@pytest.mark.parametrize('viewer', VIEWER_LAYOUTS, ids=lambda v: v.file)
def test_every_plot_title_states_its_units_in_the_time_unit_of_its_timeline(viewer):
    """
    A plot's x is the timeline's seconds, one time unit of the runs it is made for each.

    So its title says ``t [unit]``, its values' unit in brackets, rates in rad per that unit
    (never another's: the flyby's w in rad/yr over hours was ~1,800 on a 144-unit axis).
    """
    config = _layout(CONFIG / viewer.file)['configById']
    for name, panel in config.items():
        kind = name.split('!')[0]
        if kind not in ('Plot', 'StateTransitions'):
            continue
        title = panel[TITLE]
        assert f't [{viewer.time_unit}]' in title, (name, title)
        if kind == 'Plot':
            assert [u for u in _UNIT.findall(title) if u != viewer.time_unit], (name, title)
        rates = set(re.findall(r'rad/\w+', title))
        assert rates == ({viewer.rate} if name in RATE_PANELS else set()), (name, title)
    for name in ('RawMessages!status', 'RawMessages!comparison'):   # shown as published
        assert 'in yr, as published' in config[name][TITLE], name


def test_the_flyby_scripts_convert_rad_per_year_to_rad_per_hour_and_km_to_thousands():
    """The published rad/yr over HOURS_PER_YEAR (8766 h a year), every field; km / 1000."""
    config = _layout(FLYBY)['configById']
    scripts = _scripts(FLYBY)
    rate_topics = {p['value'].split('.')[0] for name in RATE_PANELS for p in config[name]['paths']}
    rate_topics &= set(scripts)
    assert len(rate_topics) == 5        # w, the model, the impacts' dw, the error, its norm
    for topic in rate_topics:
        source, output_type, code = scripts[topic]
        (hours,) = re.findall(r'const HOURS_PER_YEAR = ([\d.]+);', code)
        assert float(hours) == HOURS_PER_YEAR, topic
        fields = re.findall(r'(\w+): number', output_type)
        (returned,) = re.findall(r'return \{(.*)\};', code, re.S)
        assert sorted(re.findall(r'(\w+): [^,]+ / HOURS_PER_YEAR', returned)) == sorted(fields), (
            topic, returned)
    (perturber,) = {p['value'].split('.')[0] for p in config['Plot!perturber']['paths']}
    (returned,) = re.findall(r'return \{(.*)\};', scripts[perturber][2], re.S)
    assert returned.count('/ 1000') == 4 and '[10³ km]' in config['Plot!perturber'][TITLE]


def _feeds(path) -> dict[str, str]:
    """Return {plotted topic: the published topic behind it} (a script's input, or itself)."""
    scripts = _scripts(path)
    return {topic: scripts[topic][0] if topic in scripts else topic for topic in _references(path)}


@pytest.mark.parametrize('path', LAYOUTS, ids=lambda p: p.name)
def test_the_series_with_gaps_are_dots_not_lines_across_them(path):
    """
    Draw the series that have gaps as dots: a line would join across the gap.

    The comparator publishes nothing where its model does not apply (a flyby's encounter
    window: 1,370 of 2,881 samples compared) and the impacts are single points. Lichtblick
    1.10.8 joins every point of a series (Plot ``showLine``, PlotCoordinator.ts: default true);
    ``showLine: false`` draws the points alone.
    """
    feeds = _feeds(path)
    gappy = ('/comparison/', '/' + topics.IMPACT_EVENTS)
    for name, panel in _panels(path, 'Plot').items():
        for p in panel['paths']:
            source = feeds[p['value'].split('.')[0]]
            if source.startswith(gappy):
                assert p.get('showLine') is False and p['lineSize'] > 0, (name, p['value'])


def _seconds_per_year(scenario_file: Path) -> float:
    """Return the default time base (ROS s per yr) of a shipped scenario's recordings."""
    ignore = frozenset(topics.SIM_NODE_PARAMETERS)
    return seconds_per_year_of(load_scenario(scenario_file, ignore=ignore).time_unit)


def test_the_layout_named_for_each_kind_of_run_is_the_one_made_for_its_timeline():
    for viewer in VIEWER_LAYOUTS:
        assert (CONFIG / viewer.file).is_file(), viewer.file
    assert layout_for(_seconds_per_year(CONFIG / 'default.yaml')).file == LAYOUT.name
    assert layout_for(_seconds_per_year(CONFIG / 'fig10.yaml')).file == LAYOUT.name
    assert layout_for(_seconds_per_year(CONFIG / 'apophis_2029.yaml')).file == FLYBY.name
    for scenario in sorted(CONFIG.glob('*.yaml')):      # every shipped run has one
        assert layout_for(_seconds_per_year(scenario)) is not None, scenario.name
    line = layout_line(seconds_per_year_of('h'))
    assert FLYBY.name in line and 'rad/h' in line and 't in h' in line
    # a timeline in days (a scenario of time_unit d): none shipped, and the line says so
    assert layout_for(seconds_per_year_of('d')) is None
    assert layout_line(seconds_per_year_of('d')).startswith(
        'viewer: no shipped layout fits this recording (one second of its timeline is one d)')
    assert 'no shipped layout' in layout_line(2.5)


def test_analyze_ends_with_the_layout_for_the_recording(capsys):
    from tumble_ros.analysis.cli import command

    golden = Path(__file__).resolve().parent / 'data' / 'golden.mcap'
    assert command([str(golden)]) == 0
    last = capsys.readouterr().out.splitlines()[-1]
    assert last.startswith('viewer: open the recording') and LAYOUT.name in last, last
    assert 't in yr, w in rad/yr' in last


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


# -- room at 1280x800: Lichtblick 1.10.8's chrome, measured in headless Chromium (the panels'
# rectangles in the page at 1280x800, the layouts imported: app bar 0-44 px, the layout's
# tiles 44-724 px, toolbars and tab rows 30 px; the left sidebar, open at the start, 320 px) --
#: The area the layout tree splits: the window less the app bar, the playback bar and the left
#: sidebar (the worst case: open) [px].
SCREEN = (1280, 800)
APP_BAR = 44
PLAYBACK_BAR = 76
SIDEBAR = 320
#: A panel's toolbar (its title) and a Tab panel's row of tabs [px].
TOOLBAR = 30
TAB_BAR = 30
#: The least a panel's content needs [px]: a plot, 3 y ticks and its x axis; the 3D scene; a
#: few lines of a message. StateTransitions: 64 px a path and a 30-px x axis (its index.tsx).
MIN_CONTENT = {'Plot': 110, '3D': 250, 'RawMessages': 90}
MIN_WIDTH = 250


def _rectangles(node, config, x, y, w, h) -> dict[str, tuple[float, float, float, float]]:
    """Return {panel: (x, y, width, height) of its content} for a layout tree in that area."""
    if isinstance(node, str):
        found = {}
        if node.startswith('Tab!'):
            for tab in config[node]['tabs']:
                found.update(_rectangles(tab['layout'], config, x, y + TAB_BAR, w, h - TAB_BAR))
            return found
        return {node: (x, y + TOOLBAR, w, h - TOOLBAR)}
    share = node.get('splitPercentage', 50.0) / 100.0
    if node['direction'] == 'row':
        return {**_rectangles(node['first'], config, x, y, w * share, h),
                **_rectangles(node['second'], config, x + w * share, y, w * (1 - share), h)}
    return {**_rectangles(node['first'], config, x, y, w, h * share),
            **_rectangles(node['second'], config, x, y + h * share, w, h * (1 - share))}


@pytest.mark.parametrize('path', LAYOUTS, ids=lambda p: p.name)
def test_every_panel_has_room_at_1280x800(path):
    """No 30-pixel strips: each panel's content has the room its kind needs (events included)."""
    layout = _layout(path)
    config = layout['configById']
    width, height = SCREEN[0] - SIDEBAR, SCREEN[1] - APP_BAR - PLAYBACK_BAR
    for name, (_, _, w, h) in _rectangles(layout['layout'], config, 0, 0, width, height).items():
        kind = name.split('!')[0]
        need = (64 * len(config[name]['paths']) + 30 if kind == 'StateTransitions'
                else MIN_CONTENT[kind])
        assert h >= need and w >= MIN_WIDTH, (name, round(w), round(h), need)
