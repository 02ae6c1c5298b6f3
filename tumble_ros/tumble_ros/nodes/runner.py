"""The one ``main()`` of every node executable (the demo_nodes_py pattern, written once)."""
from __future__ import annotations

from typing import Callable

import rclpy
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node

from tumble_ros.core import ScenarioError

__all__ = ["run_node"]


def run_node(make_node: Callable[[], Node], args: list[str] | None, name: str) -> int:
    """Init rclpy, build the node, spin until SIGINT/SIGTERM or shutdown, clean up.

    Returns 0 on a normal stop, 1 when the node refused its parameters (the reason is printed,
    no traceback). A node's ``close()`` (finalise a file, say goodbye) runs before it is destroyed.
    """
    rclpy.init(args=args)
    node = None
    try:
        node = make_node()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except _rclpy.RCLError:
        # A SIGINT/SIGTERM that shuts the context down while the executor builds its wait set
        # surfaces as "context is not valid" instead of ExternalShutdownException (seen under
        # load): a shutdown all the same. Any other RCLError is a real failure.
        if rclpy.ok():
            raise
    except (ParameterException, ScenarioError, ValueError, OSError) as err:
        print(f"{name}: invalid parameters: {err}", flush=True)
        return 1
    finally:
        if node is not None:
            close = getattr(node, "close", None)
            if close is not None:
                close()
            node.destroy_node()
        rclpy.try_shutdown()
    return 0
