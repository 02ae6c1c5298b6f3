"""
rosidl_generator_py imported without its code generator by the main job (rosidl_without_generator).

In a fresh process each: after it, the package has ``import_type_support`` (what the message
modules take from it) and no ``generate_py``, its generator's imports (lark, rosidl_parser) are
not loaded, and a later import of the generator works; imported before, the package is left as
it was. The main job calls it before its imports and records with it (its nodes' publishers
import the messages' type support).
"""
from pathlib import Path
import subprocess
import sys

from test_main_job import main_job_then


def _python(code):
    return subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                          timeout=300, cwd=Path(__file__).parent)


def test_the_package_is_imported_without_its_generator():
    done = _python('import sys\n'
                   'from tumble_ros.__main__ import rosidl_without_generator\n'
                   'rosidl_without_generator()\n'
                   'import rosidl_generator_py as r\n'
                   'print(callable(r.import_type_support), hasattr(r, "generate_py"),\n'
                   '      "lark" in sys.modules, "rosidl_parser.parser" in sys.modules,\n'
                   '      "rosidl_generator_py.generate_py_impl" in sys.modules)\n'
                   'from rosidl_generator_py.generate_py_impl import generate_py\n'
                   'print(callable(generate_py))\n')
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ['True', 'False', 'False', 'False', 'False', 'True']


def test_an_imported_package_is_left_as_it_was():
    done = _python('import rosidl_generator_py as r\n'
                   'from tumble_ros.__main__ import rosidl_without_generator\n'
                   'rosidl_without_generator()\n'
                   'import sys\n'
                   'print(sys.modules["rosidl_generator_py"] is r, callable(r.generate_py))\n')
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ['True', 'True']


def test_the_main_job_records_without_the_generator(tmp_path):
    done = main_job_then(tmp_path, 'print(code, "rosidl_generator_py" in sys.modules, '
                                   '"lark" in sys.modules)\n')
    assert done.returncode == 0, done.stderr
    assert done.stdout.split()[-3:] == ['0', 'True', 'False']
    assert len(list(tmp_path.glob('recordings/short_*.mcap'))) == 1
