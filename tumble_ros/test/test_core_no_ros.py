"""The numerical core is usable without ROS: it imports no rclpy."""
import ast
import subprocess
import sys
from pathlib import Path

CORE = Path(__file__).resolve().parents[1] / "tumble_ros" / "core"


def test_core_sources_import_no_ros():
    offenders = []
    for path in CORE.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module]
            offenders += [f"{path.name}: {n}" for n in names if n.split(".")[0] in {"rclpy", "rosidl_runtime_py"}
                          or n.endswith("_msgs") or n.split(".")[0].endswith("_msgs")]
    assert not offenders
    assert len(list(CORE.rglob("*.py"))) >= 5


def test_importing_core_loads_no_rclpy():
    code = ("import sys, tumble_ros.core; from tumble_ros.core import Scenario, simulate; "
            "bad = [m for m in sys.modules if m.startswith(('rclpy', 'rosidl'))]; print(bad); "
            "sys.exit(1 if bad else 0)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stdout + done.stderr
