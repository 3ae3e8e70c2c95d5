"""Test helpers: decode Foxglove protobuf messages with the official schema carried beside them.

The schema bytes of a channel (an MCAP Schema record, or the ``schema`` of a
WebSocket advertisement) are a protobuf ``FileDescriptorSet``; the messages are
decoded with Google's ``protobuf`` runtime against it, so a message that does not
conform (a field the schema lacks, a wrong wire type) fails to parse or shows up
in ``UnknownFields()``.
"""
from __future__ import annotations

from functools import cache

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from google.protobuf.unknown_fields import UnknownFieldSet


@cache
def message_class(schema_name: str, schema_data: bytes):
    """The protobuf message class for ``schema_name`` (e.g. ``foxglove.SceneUpdate``) from a FileDescriptorSet."""
    fds = descriptor_pb2.FileDescriptorSet.FromString(schema_data)
    pool = descriptor_pool.DescriptorPool()
    for fd in fds.file:
        pool.Add(fd)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(schema_name))


def _check_no_unknown(msg) -> None:
    assert len(UnknownFieldSet(msg)) == 0, f"{msg.DESCRIPTOR.full_name} has fields the schema does not define"
    for field, value in msg.ListFields():
        if field.type != field.TYPE_MESSAGE:
            continue
        for sub in (value if not hasattr(value, "ListFields") else [value]):  # repeated or single
            _check_no_unknown(sub)


def decode(schema_name: str, schema_data: bytes, data: bytes):
    """Parse ``data`` strictly as ``schema_name``: every field known to the schema, everywhere."""
    msg = message_class(schema_name, bytes(schema_data))()
    msg.ParseFromString(data)
    _check_no_unknown(msg)
    return msg
