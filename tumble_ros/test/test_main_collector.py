"""
The main job's imports run without the garbage collector (__main__.main_job, _figure_pool).

In a fresh process: from the job's start to its figure worker's fork no collection runs, after
it they do (the recording, the analysis), and the collector is on when the job returns; the
figures are drawn. In this process: an error before the worker is forked leaves the collector
on, as it was.
"""
import gc
from pathlib import Path
import subprocess
import sys

import pytest

import tumble_ros.__main__ as entry


def test_no_collection_before_the_figure_worker_is_forked(tmp_path):
    scenario = tmp_path / 'short.yaml'
    scenario.write_text(
        'sim:\n  ros__parameters:\n    duration: 2.0\n    output_interval: 0.0002\n')
    code = ('import gc, sys\n'
            'from tumble_ros.__main__ import main\n'
            'import tumble_ros.analysis.figure_pool as pool\n'
            'events, start = [], pool.FigurePool.start\n'
            'def forked(*args, **kwargs):\n'
            '    events.append("fork")\n'
            '    return start(*args, **kwargs)\n'
            'pool.FigurePool.start = forked\n'
            'gc.callbacks.append(lambda phase, info: phase == "start" and events.append("gc"))\n'
            f'code = main([{str(scenario)!r}])\n'
            'k = events.index("fork")\n'
            'print(code, events[:k].count("gc"), events[k:].count("gc") > 0, gc.isenabled())\n')
    done = subprocess.run([sys.executable, '-c', code], cwd=tmp_path, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split()[-4:] == ['0', '0', 'True', 'True']
    figures = sorted(p.name for p in tmp_path.glob('recordings/short_*_figures/*.png'))
    assert 'omega.png' in figures and 'spectrum_wx.png' in figures


def test_an_error_before_the_fork_leaves_the_collector_on(monkeypatch):
    def fail():
        raise RuntimeError('no generator today')
    monkeypatch.setattr(entry, 'rosidl_without_generator', fail)
    assert gc.isenabled()
    with pytest.raises(RuntimeError, match='no generator today'):
        entry.main_job([str(Path(__file__).resolve().parents[1] / 'config' / 'fig9.yaml')])
    assert gc.isenabled()
