#!/usr/bin/python3
"""Compares the messages of given channels in LCM logs, byte for byte, in order per channel.
usage: log_compare.py CHANNELS A.lcmlog B.lcmlog [...]   (CHANNELS comma-separated)
       log_compare.py --count CHANNEL LOG                  (prints the number of messages)
Exit 0 when every log holds the same messages on every channel (and at least one)."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', '..',
                                'tools', 'lcmlog'))
import swf_lcmlog  # noqa: E402  (the project's LCM log reader, from the source tree)


def read(path):
    out = {}
    try:
        for record in swf_lcmlog.records(path):
            out.setdefault(record.channel, []).append(record.data)
    except swf_lcmlog.LogError as e:
        raise SystemExit(str(e)) from None
    return out


if sys.argv[1] == '--count':
    print(len(read(sys.argv[3]).get(sys.argv[2], [])))
    sys.exit(0)
channels = sys.argv[1].split(',')
logs = [(p, read(p)) for p in sys.argv[2:]]
ok = True
for c in channels:
    ref_path, ref = logs[0][0], logs[0][1].get(c, [])
    if not ref:
        print('%s: no %s messages' % (ref_path, c))
        ok = False
    for path, log in logs[1:]:
        other = log.get(c, [])
        if other != ref:
            first = next((i for i, (a, b) in enumerate(zip(ref, other)) if a != b),
                         min(len(ref), len(other)))
            print('%s vs %s: %s differs (%d vs %d messages, first difference at #%d)' %
                  (ref_path, path, c, len(ref), len(other), first))
            ok = False
        else:
            print('%s vs %s: %d %s messages identical' % (ref_path, path, len(ref), c))
sys.exit(0 if ok else 1)
