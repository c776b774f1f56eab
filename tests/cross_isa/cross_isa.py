#!/usr/bin/python3
"""Cross-ISA comparison: the flight process (swf-fsw) cross-built for aarch64 and run under qemu
against the host's (x86-64) swf-fsw on the same recorded descent.

  cross_isa.py check --sil HOST-SWF-SIL --host-fsw HOST-SWF-FSW [--frames N] [--keep DIR]
                     -- [EMULATOR ...] TARGET-SWF-FSW
  cross_isa.py compare A.lcmlog B.lcmlog

`check` records a short simulated descent with the host's swf-sil (fsw/app/config/demo.cfg, the
first N frames: stereo pairs and IMU samples), makes it a camera log (camera_log), flies it with
both swf-fsw programs (flight.cfg beside this file: demo.cfg's flight settings, `source: log`),
and compares every SWF_NAV, SWF_LANDMARKS and SWF_HAZARD message of the two recordings by its
SHA-256, per channel and in order (tests/change_indication's digests). Bit-identical outputs pass.
The aarch64 swf-fsw then replays its own recording, which must give its outputs again, bit for
bit (a descent flown on the target is replayable there).
Otherwise the first differing message of each channel is reported with its first differing
byte, the messages are decoded (lcm-gen's Python types of messages/*.lcm) and compared field by
field: the check passes when every integer field is equal and every floating-point field is within
the stated bound (ABS_BOUND, REL_BOUND), and prints the largest difference of each field.
Self-checks first prove both comparisons can fail: one byte flipped in one message of each
channel is found, and a navigation position with a flipped exponent byte is outside the bound.

Unlike tests/change_indication there is no committed reference: both programs fly the same input
on the same machine, so what may differ is only the instruction set, the compiler's code for it
and the two C libraries (Debian 12's x86-64 and arm64 glibc)."""
import argparse
import importlib
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, 'tests', 'change_indication'))
import change_indication  # noqa: E402  (the digests and the log reader are shared)

CHANNELS = change_indication.CHANNELS


def payloads(log):
    """{channel: [payload bytes]} of CHANNELS, in order per channel."""
    out = {c: [] for c in CHANNELS}
    for channel, payload in change_indication.read_log(log):
        if channel in out:
            out[channel].append(payload)
    return out


def compare(a, b):
    """Lines describing every channel where a and b differ; empty when bit-identical."""
    da, db = change_indication.output_digests(a), change_indication.output_digests(b)
    if da == db:
        return []
    pa, pb = payloads(a), payloads(b)
    report = []
    for c in CHANNELS:
        if da[c] == db[c]:
            continue
        differing = [i for i, (x, y) in enumerate(zip(pa[c], pb[c])) if x != y]
        line = '%s: %d and %d messages, %d of the common ones differ' % (
            c, len(pa[c]), len(pb[c]), len(differing))
        if differing:
            i = differing[0]
            x, y = pa[c][i], pb[c][i]
            byte = next((k for k, (u, v) in enumerate(zip(x, y)) if u != v), min(len(x), len(y)))
            line += '; first: message %d, byte %d of %d' % (i, byte, len(x))
        report.append(line)
    return report


# stereo_frame_t's `rectified` flag: after the 8-byte type hash, four int64 and one int32.
RECTIFIED_OFFSET = 8 + 4 * 8 + 4


# The stated bound (docs/aarch64.md): the two instruction sets give the same decisions (every
# integer, boolean and string field: statuses, integrity flags, hazard classes, the safe site,
# counts) and floating-point fields within ABS_BOUND + REL_BOUND |value|, a margin of more than
# ten over the largest differences measured on this descent (docs/aarch64.md says where they
# come from).
ABS_BOUND = 1e-6
REL_BOUND = 1e-6
MESSAGE_TYPES = {'SWF_NAV': 'nav_state_t', 'SWF_LANDMARKS': 'landmark_map_t',
                 'SWF_HAZARD': 'hazard_map_t'}


def message_types(workdir):
    """{channel: the lcm-gen Python type of its messages} (generated from messages/*.lcm)."""
    out = os.path.join(workdir, 'py')
    schemas = [os.path.join(ROOT, 'messages', t + '.lcm') for t in MESSAGE_TYPES.values()]
    subprocess.run(['lcm-gen', '--python', '--ppath', out] + schemas, check=True,
                   stdout=subprocess.DEVNULL)
    sys.path.insert(0, out)
    return {c: getattr(importlib.import_module('swf_msgs.' + t), t)
            for c, t in MESSAGE_TYPES.items()}


def leaves(value, name, out):
    if isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            leaves(v, '%s[%d]' % (name, i), out)
    else:
        out[name] = value


def bounded_differences(a, b, types):
    """(every field outside the bound, {(channel, field): largest |difference|}) of the
    messages of a and b, decoded field by field."""
    pa, pb = payloads(a), payloads(b)
    outside, largest = [], {}
    for c, t in types.items():
        if len(pa[c]) != len(pb[c]):
            outside.append('%s: %d and %d messages' % (c, len(pa[c]), len(pb[c])))
        for k, (x, y) in enumerate(zip(pa[c], pb[c])):
            mx, my = t.decode(x), t.decode(y)
            for field in mx.__slots__:
                fx, fy = {}, {}
                leaves(getattr(mx, field), field, fx)
                leaves(getattr(my, field), field, fy)
                for name, u in fx.items():
                    v = fy[name]
                    if u == v or (isinstance(u, float) and math.isnan(u) and math.isnan(v)):
                        continue
                    if isinstance(u, float) and math.isfinite(u) and math.isfinite(v):
                        d = abs(u - v)
                        largest[(c, field)] = max(largest.get((c, field), 0.0), d)
                        if d <= ABS_BOUND + REL_BOUND * max(abs(u), abs(v)):
                            continue
                    outside.append('%s message %d: %s is %r and %r' % (c, k, name, u, v))
    return outside, largest


def camera_log(sim_log, out):
    """The simulated descent's pairs and IMU samples as a camera would have recorded them: the
    pairs marked raw (swf-fsw then rectifies them with flight.cfg's calibrations of the same
    rig; a rectified log carries no camera model, and only swf-sil's extension knows its rig)."""
    keep = ('SWF_STEREO', 'SWF_IMU')
    with open(sim_log, 'rb') as f:
        data = f.read()
    records, pos, frames = [], 0, 0
    while pos < len(data):
        clen = int.from_bytes(data[pos + 20:pos + 24], 'big')
        dlen = int.from_bytes(data[pos + 24:pos + 28], 'big')
        record = bytearray(data[pos:pos + 28 + clen + dlen])
        channel = record[28:28 + clen].decode()
        if channel == 'SWF_STEREO':
            record[28 + clen + RECTIFIED_OFFSET] = 0
            frames += 1
        if channel in keep:
            record[4:12] = len(records).to_bytes(8, 'big')  # event numbers stay consecutive
            records.append(bytes(record))
        pos += 28 + clen + dlen
    with open(out, 'wb') as f:
        f.write(b''.join(records))
    return frames


def flipped_copy(log, out, channel, offset=-1):
    """log with one byte (offset into the first message on channel; negative: from its end)
    inverted (the self-checks)."""
    with open(log, 'rb') as f:
        data = bytearray(f.read())
    pos = 0
    while pos < len(data):
        clen = int.from_bytes(data[pos + 20:pos + 24], 'big')
        dlen = int.from_bytes(data[pos + 24:pos + 28], 'big')
        if data[pos + 28:pos + 28 + clen].decode() == channel:
            data[pos + 28 + clen + (offset if offset >= 0 else dlen + offset)] ^= 0xFF
            break
        pos += 28 + clen + dlen
    else:
        raise SystemExit('%s holds no %s message to flip' % (log, channel))
    with open(out, 'wb') as f:
        f.write(bytes(data))


def run(what, cmd):
    """`cmd` from the repository's root, where the programs find ../shared themselves."""
    start_wall, start_cpu = time.monotonic(), os.times()
    proc = subprocess.run(cmd, cwd=ROOT, stderr=subprocess.PIPE, text=True)
    end_cpu = os.times()
    cpu = (end_cpu.children_user - start_cpu.children_user +
           end_cpu.children_system - start_cpu.children_system)
    print('%s: %.1f s wall, %.1f s CPU, exit %d' % (what, time.monotonic() - start_wall, cpu,
                                                   proc.returncode))
    # 0 ok, 3 degraded: the outputs are complete either way; anything else is a failed run.
    if proc.returncode not in (0, 3):
        sys.stderr.write(proc.stderr)
        raise SystemExit('%s failed (exit %d): %s' % (what, proc.returncode, ' '.join(cmd)))


def check(args):
    workdir = args.keep or tempfile.mkdtemp(prefix='cross_isa.')
    os.makedirs(workdir, exist_ok=True)
    try:
        descent = os.path.join(workdir, 'descent.lcmlog')
        run('recording the descent (host swf-sil, %d frames)' % args.frames,
            [args.sil, '--config', os.path.join(ROOT, 'fsw/app/config/demo.cfg'),
             '--set', 'sim.frames: %d' % args.frames, '--set', 'pacing: lockstep',
             '--set', 'lcm.publish: false', '--set', 'rt.mlockall: false',
             '--set', 'rt.priority: 0', '--set', 'record.path: ' + descent])
        camera = os.path.join(workdir, 'camera.lcmlog')
        frames = camera_log(descent, camera)
        if frames != args.frames:
            raise SystemExit('the recording holds %d pairs, not %d' % (frames, args.frames))
        logs = {}
        for name, cmd in (('x86-64', [args.host_fsw]), ('aarch64', args.target)):
            logs[name] = os.path.join(workdir, name + '.lcmlog')
            run('swf-fsw on the log (%s)' % name,
                cmd + ['--config', os.path.join(HERE, 'flight.cfg'),
                       '--set', 'log.path: ' + camera, '--set', 'record.path: ' + logs[name]])
        # Every descent replayable on the flight computer: the target's recording (its frames and
        # IMU samples with its outputs) flown again by the same binary gives the same outputs.
        replay = os.path.join(workdir, 'aarch64_replay.lcmlog')
        run('swf-fsw replaying its own recording (aarch64)',
            args.target + ['--config', os.path.join(HERE, 'flight.cfg'),
                           '--set', 'log.path: ' + logs['aarch64'],
                           '--set', 'record.path: ' + replay])
        replay_report = compare(logs['aarch64'], replay)
        ok = not replay_report
        if replay_report:
            print('the aarch64 replay of its own recording differs:\n  ' +
                  '\n  '.join(replay_report))
        else:
            print('aarch64: the replay of its own recording gives the same outputs, bit for bit')
        for channel in CHANNELS:
            flipped = os.path.join(workdir, 'flipped.lcmlog')
            flipped_copy(logs['aarch64'], flipped, channel)
            found = compare(logs['aarch64'], flipped)
            if len(found) != 1 or not found[0].startswith(channel + ':'):
                print('self-check FAILED: one flipped %s byte was reported as %s' %
                      (channel, found or 'no difference'))
                ok = False
        if ok:
            print('self-check: one flipped byte is found on each of %s' % ', '.join(CHANNELS))
        types = message_types(workdir)
        flipped = os.path.join(workdir, 'flipped.lcmlog')
        # The sign and exponent byte of the first position coordinate (after the type hash and
        # three int64): a wrong navigation output must not pass as a rounding difference.
        flipped_copy(logs['aarch64'], flipped, 'SWF_NAV', 8 + 3 * 8)
        if bounded_differences(logs['aarch64'], flipped, types)[0]:
            print('self-check: a position with a flipped exponent byte is outside the bound')
        else:
            print('self-check FAILED: a position with a flipped exponent byte passed the bound')
            ok = False
        report = compare(logs['x86-64'], logs['aarch64'])
        counts = {c: len(v) for c, v in change_indication.output_digests(logs['x86-64']).items()}
        counted = ', '.join('%d %s' % (counts[c], c) for c in CHANNELS)
        if report:
            print('x86-64 and aarch64 outputs are not bit-identical:\n  ' + '\n  '.join(report))
            outside, largest = bounded_differences(logs['x86-64'], logs['aarch64'], types)
            for (c, field), d in sorted(largest.items()):
                print('  %s.%s: largest difference %.3g' % (c, field, d))
            if outside:
                print('OUTSIDE the bound (%g + %g |value|, integers equal):\n  %s' %
                      (ABS_BOUND, REL_BOUND, '\n  '.join(outside[:20])))
                ok = False
            else:
                print('x86-64 and aarch64: %s equal within %g + %g |value|, every integer field '
                      'equal' % (counted, ABS_BOUND, REL_BOUND))
        else:
            print('x86-64 and aarch64: %s bit for bit' % counted)
        if counts['SWF_HAZARD'] < 1:
            print('no hazard map was compared')
            ok = False
        return 0 if ok else 1
    finally:
        if not args.keep:
            shutil.rmtree(workdir, ignore_errors=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest='action', required=True)
    c = sub.add_parser('check')
    c.add_argument('--sil', required=True, help="the host's swf-sil")
    c.add_argument('--host-fsw', required=True, help="the host's swf-fsw")
    c.add_argument('--frames', type=int, default=10)
    c.add_argument('--keep', help='keep the logs in this directory')
    c.add_argument('target', nargs=argparse.REMAINDER,
                   help="-- then the target's swf-fsw, after its emulator")
    p = sub.add_parser('compare')
    p.add_argument('a')
    p.add_argument('b')
    args = parser.parse_args()
    if args.action == 'compare':
        report = compare(args.a, args.b)
        print('\n'.join(report) if report else 'bit-identical')
        return 1 if report else 0
    if args.target[:1] == ['--']:
        args.target = args.target[1:]
    if not args.target:
        parser.error('check: the target swf-fsw (after --) is missing')
    for path in (args.sil, args.host_fsw):
        if not os.access(path, os.X_OK):
            raise SystemExit('%s is not built: the check needs the host release build '
                             '(tools/run test builds it first)' % path)
    return check(args)


if __name__ == '__main__':
    sys.exit(main())
