#!/usr/bin/env python3
"""Every swf-* program the build makes, and tools/run, follows the command-line convention
(docs/cli.md): --help exits 0 and prints the usage; --version exits 0 and prints the version and
the commit; an unknown option is refused with exit 2 naming it; an output in a directory that does
not exist is written there (the directory created); a JSON summary parses as strict JSON (no
NaN / Infinity) and echoes the run (`"run": {"tool": NAME, ...}`).

The program list comes from the build (swf_programs.txt: every executable target named swf-*),
so a new program without a case below fails this test until it gets one.

usage: cli_convention_test.py PROGRAMS_TXT REPO_DIR SHARED_DIR
"""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

PROGRAMS_TXT, REPO, SHARED = sys.argv[1:4]
DATA = os.path.join(SHARED, 'data')
EUROC = os.path.join(DATA, 'euroc-v101')
KITTI_VO = os.path.join(DATA, 'kitti-vo')
failures = []


def run(cmd, timeout=60, **kw):
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, cwd=REPO, **kw)


def check(name, ok, why):
    print('%-14s %s %s' % (name, 'ok  ' if ok else 'FAIL', why))
    if not ok:
        failures.append('%s: %s' % (name, why))


def common(name, path):
    r = run([path, '--help'])
    check(name, r.returncode == 0 and re.search(r'usage', r.stdout, re.I) is not None,
          '--help: exit %d, usage on stdout' % r.returncode)
    r = run([path, '--version'])
    pattern = r'^%s \d+\.\d+\.\d+ \(commit ([0-9a-f]{7,40}(-dirty)?|unknown)\)$' % re.escape(name)
    check(name, r.returncode == 0 and re.match(pattern, r.stdout.strip()) is not None,
          '--version: exit %d, %r' % (r.returncode, r.stdout.strip()))
    r = run([path, '--no-such-option-xyz'])
    check(name, r.returncode == 2 and '--no-such-option-xyz' in r.stderr,
          'unknown option: exit %d, %r' % (r.returncode, r.stderr.strip()[:120]))


def euroc_image(cam, index):
    names = sorted(os.listdir(os.path.join(EUROC, 'mav0', cam, 'data')))
    return os.path.join(EUROC, 'mav0', cam, 'data', names[index])


# A private network namespace for the GigE fake cameras (root, or an unprivileged user namespace).
UNSHARE = ['unshare', '-n'] if os.geteuid() == 0 else ['unshare', '-rn']
FLIGHT_SETS = ['--set', 'rt.mlockall: false', '--set', 'rt.priority: 0', '--set',
               'lcm.publish: false']


def output_cases(programs, work):
    """name -> (command, the output it must write inside a directory that did not exist). Run in
    order: later cases use earlier outputs (the simulated descent's log). SUMMARY below names the
    cases whose output is a JSON summary, or which write one beside it."""
    new = lambda *parts: os.path.join(work, 'missing', *parts)  # noqa: E731
    sil_log = new('sil', 'descent.lcmlog')
    euroc_log = new('convert', 'euroc.lcmlog')
    calib = new('convert', 'calib')
    fsw_cfg = os.path.join(work, 'euroc.cfg')
    with open(fsw_cfg, 'w') as f:
        f.write('source: log\nlog.path: %s\ncamera.left_calibration: %s/left.yaml\n'
                'camera.right_calibration: %s/right.yaml\npacing: lockstep\nrate_hz: 20\n'
                'max_disparity_px: 128\ninitial: position\ninitial.position_m: 0 0 1\n'
                % (euroc_log, calib, calib))
    test_cfg = os.path.join(REPO, 'fsw/app/config/test.cfg')
    sil = [programs['swf-sil'], '--config', test_cfg, '--set', 'sim.frames: 6'] + FLIGHT_SETS
    return [
        ('swf-sil', sil + ['--set', 'record.path: ' + sil_log,
                           '--set', 'summary.path: ' + new('sil', 'summary.json')],
         new('sil', 'summary.json')),
        ('swf-replay', [programs['swf-replay'], '--config', test_cfg, '--log', sil_log,
                        '--record', new('replay', 'r.lcmlog')] + FLIGHT_SETS,
         new('replay', 'r.lcmlog')),
        ('swf-judge', [programs['swf-judge'], sil_log, '--json', new('judge', 'j.json')],
         new('judge', 'j.json')),
        ('swf-plot', [programs['swf-plot'], sil_log, '--out', new('plot')],
         new('plot', 'trajectory.png')),
        ('swf-convert', [programs['swf-convert'], 'euroc', EUROC, '--out', euroc_log,
                         '--calib-out', calib, '--max-frames', '4'], euroc_log),
        ('swf-fsw', [programs['swf-fsw'], '--config', fsw_cfg, '--set',
                     'summary.path: ' + new('fsw', 'summary.json')] + FLIGHT_SETS,
         new('fsw', 'summary.json')),
        ('swf-eval', [programs['swf-eval'], 'kitti', os.path.join(DATA, 'kitti-odometry-excerpt'),
                      '--frames', '3', '--out', new('eval')],
         new('eval', 'kitti_odometry.json')),
        ('swf-vo-synth', [programs['swf-vo-synth'], '--calib',
                          os.path.join(KITTI_VO, 'VO_calibration.txt'), '--out', new('synth'),
                          '--poses', '4', '--landmarks', '40', '--observations', '120'],
         new('synth', 'VO_stereo_factors.txt')),
        ('swf-track', [programs['swf-track'], 'rectify',
                       os.path.join(EUROC, 'mav0/cam0/sensor.yaml'),
                       os.path.join(EUROC, 'mav0/cam1/sensor.yaml'), euroc_image('cam0', 0),
                       euroc_image('cam1', 0), new('track', 'rectified.png')],
         new('track', 'rectified.png')),
        ('swf-hazard', [programs['swf-hazard'], 'map', new('hazard', 'map.png'), '--width', '64',
                        '--height', '48', '--shared', SHARED], new('hazard', 'map.png')),
        ('swf-sim', [programs['swf-sim'], '--out', new('sim'), '--scenario', 'lab', '--frames',
                     '1', '--shared', SHARED], new('sim', 'poses.csv')),
        ('swf-guidance', [programs['swf-guidance'], '--url', 'memq://', '--timeout', '0.3',
                          '--quiet', '--map-out', new('guidance', 'map.txt')],
         new('guidance', 'map.txt')),
        ('swf-view', [programs['swf-view'], '--lcm-url', 'memq://', '--port', '0', '--timeout',
                      '0.3', '--url-file', new('view', 'url.txt')], new('view', 'url.txt')),
        ('swf-grab', UNSHARE + ['sh', '-c',
                      'ip link set lo up && ip addr add 127.0.0.2/8 dev lo && exec "$0" "$@"',
                      programs['swf-grab'], 'grab', '--source', 'aravis', '--fake-gv', '--left',
                      '127.0.0.1', '--right', '127.0.0.2', '--trigger', 'software', '--width',
                      '64', '--height', '48', '--pairs', '2', '--out', new('grab')],
         new('grab', 'left_000001.png')),
    ]


# name -> a further summary a case writes beside its output (a .json output is checked too).
SUMMARY = {'swf-sim': 'summary.json', 'swf-vo-synth': 'summary.json',
           'swf-eval': 'kitti_odometry_error.json'}


def _refuse_constant(name):
    raise ValueError('%s is not JSON' % name)


def check_summary(name, path):
    """A summary: strict JSON whose "run" names the program."""
    try:
        with open(path) as f:
            summary = json.load(f, parse_constant=_refuse_constant)
    except (OSError, ValueError) as e:
        check(name, False, 'summary %s: %s' % (os.path.basename(path), e))
        return
    run = summary.get('run') if isinstance(summary, dict) else None
    check(name, isinstance(run, dict) and run.get('tool') == name,
          'summary %s echoes the run (run.tool %r)' % (
              os.path.basename(path), run.get('tool') if isinstance(run, dict) else None))


def measurements_refused(swf_eval, work):
    """swf-eval's --measurements FILE naming a file its own report writes (once silently
    overwritten by it): exit 2 before any run, saying so, and nothing written; relative to the
    working directory and through `..` as well."""
    out = os.path.join(work, 'refused')
    cases = [(['euroc', EUROC, '--out', out, '--measurements', os.path.join(out, 'euroc.json')],
              None),
             (['euroc', EUROC, '--loop-seconds', '5', '--out', out, '--measurements',
               os.path.join(out, '..', 'refused', 'euroc_loop_swf_tum.txt')], None),
             (['kitti', os.path.join(DATA, 'kitti-odometry-excerpt'), '--out', '.',
               '--measurements', 'kitti_odometry.md'], out)]
    for args, cwd in cases:
        if cwd:
            os.makedirs(cwd, exist_ok=True)
        r = subprocess.run([swf_eval] + args, capture_output=True, text=True, timeout=60,
                           cwd=cwd or REPO)
        written = os.listdir(out) if os.path.isdir(out) else []
        check('swf-eval', r.returncode == 2 and 'own report file' in r.stderr and not written,
              '--measurements naming the report\'s %s: exit %d, %r, written %s' % (
                  os.path.basename(args[-1]), r.returncode, r.stderr.strip()[:100], written))


# Programs that write no file: their output is stdout (a JSON object).
STDOUT_ONLY = {'swf-vo': 'prints one JSON object on stdout'}


def main():
    programs = {}
    with open(PROGRAMS_TXT) as f:
        for line in f:
            if line.strip():
                name, path = line.strip().split('=', 1)
                programs[name] = path
    check('build', len(programs) >= 14, '%d swf-* programs listed' % len(programs))
    for name in sorted(programs):
        if not os.access(programs[name], os.X_OK):
            check(name, False, 'not built: %s' % programs[name])
            continue
        common(name, programs[name])
    work = tempfile.mkdtemp(prefix='cli_convention.')
    try:
        cases = output_cases(programs, work)
        covered = {c[0] for c in cases} | set(STDOUT_ONLY)
        for name in sorted(set(programs) - covered):
            check(name, False, 'no output-directory case in tests/cli/cli_convention_test.py')
        for name, cmd, output in cases:
            if name not in programs:
                continue
            if cmd[0] == 'unshare' and run(UNSHARE + ['true']).returncode != 0:
                check(name, False, 'cannot create a network namespace (run as root)')
                continue
            r = run(cmd, timeout=120)
            made = os.path.isfile(output)  # a guidance map with no landmark is empty
            partial = [p for p in _walk(os.path.dirname(output)) if '.partial' in p]
            check(name, made and not partial and r.returncode in (0, 1, 3),
                  'output in a new directory: exit %d, %s%s%s' % (
                      r.returncode, os.path.relpath(output, work),
                      '' if made else ' NOT WRITTEN',
                      (' partial files left: %s' % partial) if partial else '') +
                  ('' if made else '\n' + r.stderr[-600:]))
            if made and output.endswith('.json'):
                check_summary(name, output)
            if name in SUMMARY:
                check_summary(name, os.path.join(os.path.dirname(output), SUMMARY[name]))
        if 'swf-eval' in programs:
            measurements_refused(programs['swf-eval'], work)
        for name, why in STDOUT_ONLY.items():
            check(name, True, 'no output file (%s)' % why)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    # tools/run: the same answers for its verbs.
    tools_run = os.path.join(REPO, 'tools/run')
    r = run([tools_run, '--help'])
    check('tools/run', r.returncode == 0 and 'usage: tools/run' in r.stdout and
          'set -e' not in r.stdout, '--help: exit %d' % r.returncode)
    r = run([tools_run, '--version'])
    check('tools/run', r.returncode == 0 and re.match(r'^tools/run \S+ \(commit ', r.stdout),
          '--version: exit %d, %r' % (r.returncode, r.stdout.strip()))
    r = run([tools_run, '--no-such-option-xyz'])
    check('tools/run', r.returncode == 2 and '--no-such-option-xyz' in r.stderr,
          'unknown verb: exit %d' % r.returncode)
    for verb, value in (('fuzz', 'abc'), ('fuzz', '0'), ('soak', '-3'), ('soak', '2x')):
        r = run([tools_run, verb, value])
        check('tools/run', r.returncode == 2 and repr(value) in r.stderr.replace('"', "'"),
              '%s %s: exit %d, %r' % (verb, value, r.returncode, r.stderr.strip()))
    if failures:
        print('\n%d failures:\n  %s' % (len(failures), '\n  '.join(failures)))
        return 1
    print('cli convention: every program passes')
    return 0


def _walk(top):
    for root, _, files in os.walk(top):
        for f in files:
            yield os.path.join(root, f)


if __name__ == '__main__':
    sys.exit(main())
