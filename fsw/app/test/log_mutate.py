#!/usr/bin/env python3
"""Writes a damaged copy of an LCM log, for the crafted-log cases of process_test.sh.

usage: log_mutate.py IN OUT CHANNEL OP K
  drop K       leave out the K-th record on CHANNEL (0-based)
  duplicate K  write the K-th record on CHANNEL twice
  swap K       write the K-th and (K+1)-th records on CHANNEL in the other order
  neglen K     set the K-th record's stereo_frame_t.num_bytes to -1
  unrectify K  mark every record on CHANNEL from the K-th on as not rectified (raw camera frames)
"""
import os
import struct
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..",
                                "tools", "lcmlog"))
import swf_lcmlog  # noqa: E402  (the project's LCM log reader, from the source tree)

NUM_BYTES = 8 + 86 + 8  # stereo_frame_t.num_bytes: fingerprint, fixed fields, width, height
RECTIFIED = 8 + 4 * 8 + 4  # stereo_frame_t.rectified: fingerprint, four int64, dropped_before


def records(path):
    """(event number, utime, channel, payload as a bytearray) of every record, in order."""
    return [(r.eventnum, r.utime, r.channel, bytearray(r.data)) for r in swf_lcmlog.records(path)]


def main():
    src, dst, channel, op, k = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4], int(sys.argv[5])
    out = []
    recs = records(src)
    stereo = [i for i, r in enumerate(recs) if r[2] == channel]
    target = stereo[k]
    for i, rec in enumerate(recs):
        if i == target and op == "drop":
            continue
        if i == target and op == "swap":
            out.append(recs[stereo[k + 1]])
            out.append(rec)
            continue
        if op == "swap" and i == stereo[k + 1]:
            continue
        if i == target and op == "neglen":
            rec[3][NUM_BYTES:NUM_BYTES + 4] = struct.pack(">i", -1)
        if op == "unrectify" and i in stereo and i >= target:
            rec[3][RECTIFIED] = 0
        out.append(rec)
        if i == target and op == "duplicate":
            out.append(rec)
    with open(dst, "wb") as f:
        for n, (_, utime, ch, payload) in enumerate(out):
            f.write(swf_lcmlog.HEADER.pack(swf_lcmlog.SYNC_WORD, n, utime, len(ch), len(payload)))
            f.write(ch.encode())
            f.write(payload)


if __name__ == "__main__":
    main()
