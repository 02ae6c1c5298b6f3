"""A node whose set-up either completes or leaves nothing behind."""
from __future__ import annotations

from rclpy.node import Node

__all__ = ['GuardedNode']


class GuardedNode(Node):
    """
    Run the subclass's ``_set_up(*set_up_args)`` after the rclpy Node is created.

    If the set-up raises (a refused parameter, an unwritable file), the node is destroyed
    before the error propagates: a half-built node left in its context outlived the refusal
    and, in a long test process, preceded a crash.
    """

    def __init__(self, name: str, *set_up_args, **kwargs) -> None:
        super().__init__(name, **kwargs)
        try:
            self._set_up(*set_up_args)
        except BaseException:
            self.destroy_node()
            raise

    def _set_up(self, *args) -> None:
        raise NotImplementedError
