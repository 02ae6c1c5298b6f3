"""
MCAP writing and reading, lookup of ROS message definitions, and ensemble stores.

Writes rosbag2-compatible MCAP (profile ``ros2``, ``ros2msg`` schemas with their dependencies
concatenated, ``cdr`` messages) and reads it back. Message definitions are looked up through the
ament index and, because sourcing install/setup.bash can drop the venv from AMENT_PREFIX_PATH,
also under ``sys.prefix``. Ensemble results go to labelled xarray/Zarr stores
(:mod:`.ensemble_store`: :class:`EnsembleStore` writes them chunk by chunk, :func:`open_ensemble`
reads them).
"""  # noqa: A005 (tumble_ros.io is a subpackage: absolute imports never confuse it with io)

from .columns import (BackgroundColumns, FlatLayout, gather_in_background, MessageEncoder,
                      MessageTemplate, read_columns, sample_values, TopicColumns,
                      written_columns)
from .ensemble_store import ensemble_variable, EnsembleStore, EnsembleStoreError, open_ensemble
from .mcap_reader import (McapError, McapSummary, read_messages, RecordedMessage, summarize,
                          TopicSummary)
from .mcap_writer import McapWriter, offered_qos_yaml, WrittenMessages
from .msgdefs import message_definition, MessageDefinitionError, normalize_type_name, type_hash

__all__ = [
    'EnsembleStore',
    'EnsembleStoreError',
    'ensemble_variable',
    'open_ensemble',
    'BackgroundColumns',
    'FlatLayout',
    'gather_in_background',
    'MessageEncoder',
    'MessageTemplate',
    'read_columns',
    'sample_values',
    'TopicColumns',
    'written_columns',
    'WrittenMessages',
    'McapError',
    'McapSummary',
    'McapWriter',
    'MessageDefinitionError',
    'RecordedMessage',
    'TopicSummary',
    'message_definition',
    'normalize_type_name',
    'offered_qos_yaml',
    'read_messages',
    'summarize',
    'type_hash',
]
