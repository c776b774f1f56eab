"""swf_lcmlog: an LCM log read into Python values and numpy arrays, without any LCM module.

Debian 12 has no python3-lcm; the log format is simple and lcm-gen's Python types need only the
standard library, so this package is the whole reader:

  records(path)        every record, framing checked: Record(index, offset, eventnum, utime,
                       channel, data)
  messages(path)       every record with its payload decoded into the generated type
                       (swf_msgs.<type>, chosen by the payload's fingerprint, not by the channel
                       name; None for a type this build does not know)
  to_arrays(message)   one message's fields as numpy arrays (sequences) and Python scalars
  table(path, channel) every message of one channel, each field stacked over the messages
  to_json(message)     one message's fields as JSON values (the form `--dump` prints)

A record whose framing is broken (truncated header, wrong sync word, a length past the end of the
file) or whose payload does not decode as its type (too short, a negative or too long array
length, trailing bytes) raises LogError, which names the file, the record and its byte offset.

The generated types (package swf_msgs) come from the build: `cmake --build` writes them, and a
copy of this package, to build/<preset>/python; put that directory on PYTHONPATH (or run
build/<preset>/bin/swf-lcmlog, which does). tools/lcmlog/README.md has examples.
"""
import io
import math
import os
import struct
from dataclasses import dataclass

SYNC_WORD = 0xEDA1DA01
# sync word, event number, timestamp (microseconds), channel length, data length
HEADER = struct.Struct('>IqqII')
# liblcm's own log reader refuses channel names this long (lcm/eventlog.c).
MAX_CHANNEL_LENGTH = 1000
FINGERPRINT_SIZE = 8


class LogError(Exception):
    """A log that is not a well-formed LCM log, or a payload that does not decode as its type."""


@dataclass(frozen=True)
class Record:
    index: int      # 0-based position in the log
    offset: int     # byte offset of the record's sync word
    eventnum: int
    utime: int      # the logger's receive time, microseconds
    channel: str
    data: bytes     # the payload: type fingerprint, then the encoded message


@dataclass(frozen=True)
class Message:
    record: Record
    type_name: str  # the generated type's name, or None when this build does not know it
    value: object   # the decoded swf_msgs.<type> instance, or None


def records(path):
    """Yields every Record of the LCM log at path, in order; LogError on damaged framing."""
    size = os.path.getsize(path)
    with open(path, 'rb') as f:
        offset, index = 0, 0
        while offset < size:
            where = '%s: record %d at byte %d' % (path, index, offset)
            header = f.read(HEADER.size)
            if len(header) < HEADER.size:
                raise LogError('%s: truncated header (%d of %d bytes before the end of the file)' %
                               (where, len(header), HEADER.size))
            sync, eventnum, utime, channel_length, data_length = HEADER.unpack(header)
            if sync != SYNC_WORD:
                raise LogError('%s: sync word 0x%08X, expected 0x%08X (not an LCM log, or '
                               'damaged)' % (where, sync, SYNC_WORD))
            if not 0 < channel_length < MAX_CHANNEL_LENGTH:
                raise LogError('%s: channel length %d out of range (1..%d)' %
                               (where, channel_length, MAX_CHANNEL_LENGTH - 1))
            remaining = size - offset - HEADER.size
            if channel_length + data_length > remaining:
                raise LogError('%s: truncated: the header declares %d channel and %d data bytes, '
                               'the file holds %d more' %
                               (where, channel_length, data_length, remaining))
            try:
                channel = f.read(channel_length).decode('ascii')
            except UnicodeDecodeError as e:
                raise LogError('%s: channel name is not ASCII (%s)' % (where, e)) from None
            data = f.read(data_length)
            yield Record(index, offset, eventnum, utime, channel, data)
            offset += HEADER.size + channel_length + data_length
            index += 1


def message_types():
    """{packed fingerprint: generated class} of every type in the swf_msgs package."""
    try:
        import swf_msgs
    except ImportError:
        raise LogError('the generated message types (package swf_msgs) are not on the Python '
                       'path: build the project and add build/<preset>/python to PYTHONPATH, '
                       'or run build/<preset>/bin/swf-lcmlog') from None
    types = {}
    for name in dir(swf_msgs):
        cls = getattr(swf_msgs, name)
        if isinstance(cls, type) and hasattr(cls, '_get_packed_fingerprint'):
            types[cls._get_packed_fingerprint()] = cls
    return types


class _CheckedBuffer(io.BytesIO):
    """The payload as lcm-gen's decoders read it, refusing what they would silently accept: a
    negative length (BytesIO.read(-n) reads to the end) and a read past the end (which would
    come back short)."""

    def read(self, n=-1):
        if n is None or n < 0:
            raise LogError('a negative array length (%r)' % n)
        available = len(self.getbuffer()) - self.tell()
        if n > available:
            raise LogError('needs %d more bytes at payload byte %d, %d remain' %
                           (n, self.tell(), available))
        return super().read(n)


def decode(record, types=None, source='log'):
    """The record's payload as its generated type: (type name, value), or (None, None) when the
    fingerprint is not one of this build's types. LogError, naming `source` (the log's path) and
    the record, when it does not decode."""
    types = message_types() if types is None else types
    where = '%s: record %d at byte %d (channel %s)' % (source, record.index, record.offset,
                                                       record.channel)
    if len(record.data) < FINGERPRINT_SIZE:
        raise LogError('%s: payload of %d bytes has no type fingerprint' %
                       (where, len(record.data)))
    cls = types.get(record.data[:FINGERPRINT_SIZE])
    if cls is None:
        return None, None
    buf = _CheckedBuffer(record.data)
    buf.seek(FINGERPRINT_SIZE)
    try:
        value = cls._decode_one(buf)
    except (LogError, struct.error, ValueError, UnicodeDecodeError) as e:
        raise LogError('%s: payload does not decode as %s: %s' % (where, cls.__name__, e)) from None
    if buf.tell() != len(record.data):
        raise LogError('%s: %d bytes after the end of the %s message' %
                       (where, len(record.data) - buf.tell(), cls.__name__))
    return cls.__name__, value


def messages(path, channels=None):
    """Yields a Message for every record of the log (only those on `channels`, when given)."""
    types = message_types()
    for record in records(path):
        if channels is not None and record.channel not in channels:
            continue
        type_name, value = decode(record, types, path)
        yield Message(record, type_name, value)


def fields(value):
    """(name, Python value) of every field of a decoded message, in schema order."""
    return [(name, getattr(value, name)) for name in value.__slots__]


def to_arrays(value):
    """{field: value} with every sequence field as a numpy array (bytes as uint8, float32 fields
    as float64 arrays holding the float32 values exactly; a [n][k] field has shape (n, k)) and
    every scalar as itself."""
    import numpy
    out = {}
    for name, v in fields(value):
        if isinstance(v, (bytes, bytearray)):
            out[name] = numpy.frombuffer(v, dtype=numpy.uint8)
        elif isinstance(v, (list, tuple)):
            out[name] = numpy.array(v)
        else:
            out[name] = v
    return out


def table(path, channel):
    """Every message on `channel` with each field stacked over the messages: a numpy array with
    the messages along axis 0 where every message has the field in the same shape, else a list
    of per-message arrays (variable-length fields). Also 'log_utime': each record's log time."""
    import numpy
    rows = [(m.record.utime, to_arrays(m.value)) for m in messages(path, {channel})
            if m.value is not None]
    if not rows:
        return {}
    out = {'log_utime': numpy.array([u for u, _ in rows], dtype=numpy.int64)}
    for name in rows[0][1]:
        column = [numpy.asarray(r[name]) for _, r in rows]
        if len({c.shape for c in column}) == 1 and column[0].dtype != object:
            out[name] = numpy.stack(column)
        else:
            out[name] = column
    return out


def to_json(value):
    """A decoded message as JSON values: floats that are not finite become the strings "NaN",
    "Infinity" and "-Infinity" (JSON has no such numbers), bytes become lists of integers; a
    nested array becomes nested lists."""
    def convert(v):
        if isinstance(v, float):
            if math.isnan(v):
                return 'NaN'
            if math.isinf(v):
                return 'Infinity' if v > 0 else '-Infinity'
            return v
        if isinstance(v, (bytes, bytearray)):
            return list(v)
        if isinstance(v, (list, tuple)):
            return [convert(x) for x in v]
        return v
    return {name: convert(v) for name, v in fields(value)}
