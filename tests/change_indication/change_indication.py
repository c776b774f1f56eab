#!/usr/bin/python3
"""Change indication (PX4-style): the demo descent's navigation, landmark and hazard outputs
against a committed reference, bit for bit.

  change_indication.py check  SWF-FSW [--reference FILE]   exit 0 when the outputs are unchanged
  change_indication.py update SWF-FSW [--reference FILE]   rewrites the reference

`check` flies the demo (fsw/app/config/demo.cfg, lockstep, recorded, not published) and digests
every SWF_NAV, SWF_LANDMARKS and SWF_HAZARD message of the recording: one line per message with
its frame and a SHA-256 of its bytes. Any numerical change anywhere in the chain (simulator,
front end, filter, hazard mapper, encoders) changes a line; the first differing line says which
output of which frame moved first. When numerics change on purpose, `update` writes the new
reference, and the change shows in review as a diff of this file.

The bits depend on the C library's transcendental functions, which glibc picks per CPU (e.g. FMA
variants). The reference therefore records a fingerprint of this machine's libm (Python's math
module calls the same functions). On a machine whose fingerprint differs, a bit-for-bit
comparison would only test the CPU, so `check` says so and compares the summary's accuracy
figures within a tolerance instead: a weaker check, reported as such, never a silent pass."""
import argparse
import hashlib
import json
import math
import os
import struct
import subprocess
import sys
import tempfile

CHANNELS = ('SWF_NAV', 'SWF_LANDMARKS', 'SWF_HAZARD')
# Summary figures compared when the bits cannot be (relative tolerance).
SUMMARY_FIELDS = ('pose_rms_error_m', 'final_pose_error_m', 'landmark_rms_error_m',
                  'mean_position_nees')
SUMMARY_TOLERANCE = 0.02
HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
DEFAULT_REFERENCE = os.path.join(HERE, 'demo_reference.txt')
sys.path.insert(0, os.path.join(ROOT, 'tools', 'lcmlog'))
import swf_lcmlog  # noqa: E402  (the project's LCM log reader, from the source tree)


def libm_fingerprint():
    """A hash of libm's results on fixed arguments: equal fingerprints, equal functions."""
    h = hashlib.sha256()
    for i in range(1, 4001):
        x = i * 0.0137 - 27.3
        y = (i % 97) * 0.731 + 0.01
        values = (math.sin(x), math.cos(x), math.tan(x * 0.05), math.atan2(x, y), math.atan(x),
                  math.exp(x * 0.1), math.log(y), math.pow(y, 0.37 + x * 0.01),
                  math.asin(math.sin(x) * 0.999), math.acos(math.cos(x) * 0.999))
        h.update(struct.pack('<10d', *values))
    return h.hexdigest()[:32]


def read_log(path):
    """(channel, payload) of every record of an LCM log, in order; exits naming a damaged record."""
    try:
        for record in swf_lcmlog.records(path):
            yield record.channel, record.data
    except swf_lcmlog.LogError as e:
        raise SystemExit(str(e)) from None


def fly_demo(fsw, workdir):
    log = os.path.join(workdir, 'demo.lcmlog')
    summary = os.path.join(workdir, 'summary.json')
    cmd = [fsw, '--config', os.path.join(ROOT, 'fsw/app/config/demo.cfg'),
           '--set', 'pacing: lockstep', '--set', 'lcm.publish: false',
           '--set', 'rt.mlockall: false', '--set', 'rt.priority: 0',
           '--set', 'record.path: ' + log, '--set', 'summary.path: ' + summary]
    # From the repository's root, where swf-sil finds ../shared (or SWF_SHARED_DIR) itself.
    run = subprocess.run(cmd, cwd=ROOT, stderr=subprocess.PIPE, text=True)
    if run.returncode not in (0, 3):
        sys.stderr.write(run.stderr)
        raise SystemExit('the demo failed (exit %d): %s' % (run.returncode, ' '.join(cmd)))
    return log, summary


def digest(log, summary):
    """The reference text of one demo run."""
    with open(summary) as f:
        s = json.load(f)
    lines = ['# Change-indication reference of the demo descent (tests/change_indication).',
             '# Regenerate only for an intended numerical change: change_indication.py update.',
             'libm %s' % libm_fingerprint(),
             'result %s' % s['result']]
    for field in SUMMARY_FIELDS:
        lines.append('summary %s %r' % (field, s[field]))
    messages = output_digests(log)
    for c in CHANNELS:
        lines += ['%s %d %s' % (c, i, h) for i, h in enumerate(messages[c])]
    return '\n'.join(lines) + '\n'


def output_digests(log):
    """{channel: [SHA-256 prefix of each message]} of CHANNELS in a recording (also used by
    tests/cross_isa). Per channel, in the order of that channel: the hazard group runs on its own
    thread, so its records interleave with the frame group's differently from run to run."""
    messages = {c: [] for c in CHANNELS}
    for channel, payload in read_log(log):
        if channel in messages:
            messages[channel].append(hashlib.sha256(payload).hexdigest()[:24])
    for c in CHANNELS:
        if not messages[c]:
            raise SystemExit('%s holds no %s message' % (log, c))
    return messages


def fields(text, kind):
    return {tuple(l.split()[:-1]): l.split()[-1] for l in text.splitlines()
            if l.startswith(kind + ' ')}


def compare(reference, current):
    ref_libm = fields(reference, 'libm')
    cur_libm = fields(current, 'libm')
    if ref_libm != cur_libm:
        print('this machine\'s libm differs from the one the reference was made with: the bits '
              'cannot be compared; comparing the summary within %.0f %% instead' %
              (100 * SUMMARY_TOLERANCE))
        ok = fields(reference, 'result') == fields(current, 'result')
        ref_s, cur_s = fields(reference, 'summary'), fields(current, 'summary')
        for key, value in ref_s.items():
            a, b = float(value), float(cur_s[key])
            good = abs(a - b) <= SUMMARY_TOLERANCE * abs(a)
            print('  %s: reference %s, now %s%s' % (key[1], a, b, '' if good else '  CHANGED'))
            ok = ok and good
        return ok
    ref_lines, cur_lines = reference.splitlines(), current.splitlines()
    if ref_lines == cur_lines:
        counts = {c: sum(1 for l in cur_lines if l.startswith(c + ' ')) for c in CHANNELS}
        print('unchanged: %s bit for bit' % ', '.join('%d %s' % (counts[c], c) for c in CHANNELS))
        return True
    for i, (a, b) in enumerate(zip(ref_lines, cur_lines)):
        if a != b:
            print('changed at reference line %d:\n  reference: %s\n  now:       %s' % (i + 1, a, b))
            break
    else:
        print('changed: %d lines in the reference, %d now' % (len(ref_lines), len(cur_lines)))
    print('if the change is intended: %s update <swf-sil>' % os.path.relpath(__file__, ROOT))
    return False


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('action', choices=('check', 'update'))
    parser.add_argument('fsw', help='the swf-sil executable')
    parser.add_argument('--reference', default=DEFAULT_REFERENCE)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as workdir:
        current = digest(*fly_demo(args.fsw, workdir))
    if args.action == 'update':
        with open(args.reference, 'w') as f:
            f.write(current)
        print('wrote %s' % args.reference)
        return 0
    with open(args.reference) as f:
        reference = f.read()
    return 0 if compare(reference, current) else 1


if __name__ == '__main__':
    sys.exit(main())
