#!/usr/bin/python3
"""Instructions per frame and per stage of the flight process (swf-fsw) on a recorded stretch of
the demo descent: on the host's instruction set with callgrind, and on the flight computer's
(aarch64) with qemu-aarch64 and the stage counter plugin (stage_count_plugin.cpp); and from
these, frame-time estimates for Cortex-A53 and A72-class cores against the 15 Hz period.

  stage_profile.py --sil SWF-SIL --fsw SWF-FSW --plugin LIBSWF_STAGE_COUNT.so
                   [--target-fsw AARCH64-SWF-FSW [--emulator 'qemu-aarch64 -L /']]
                   [--frames N] [--size WxH]... [--json FILE] [--check]

The descent is recorded by the host's swf-sil (fsw/app/config/demo.cfg at each size) and made a
camera log as in tests/cross_isa; swf-fsw flies it with tests/cross_isa/flight.cfg and ideal
pinhole calibrations of the simulated rig at that size. The plugin is first run on the host's own
swf-fsw under qemu-x86_64 and its counts compared with callgrind's, stage by stage: the same
instructions counted two independent ways. --check fails (exit 1) when they disagree by more than
CHECK_TOLERANCE, or when a stage executed nothing; a run that fails stops it (exit 1)."""
import argparse
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, 'tests', 'cross_isa'))
import cross_isa  # noqa: E402  (the recording and the camera log are the cross-ISA test's)

# Stage: the functions (demangled-name prefixes) whose inclusive cost it is. "loop" is the frame
# group's own code (FlightLoop::Run and Cycle: pacing, bookkeeping, the output hand-over) and the
# stage functions' caller; "hazard_loop" is the hazard thread's.
STAGES = [
    ('loop', ['swf::app::FlightLoop::Run()', 'swf::app::FlightLoop::Cycle(']),
    ('acquire', ['swf::drivers::LogStereoSource::Next(']),
    ('rectify', ['swf::app::Pipeline::Rectify(']),
    ('track', ['swf::app::Pipeline::Track()']),
    ('estimate', ['swf::app::Pipeline::Estimate(']),
    ('publish', ['swf::app::FlightLoop::PublishNav()']),
    ('map', ['swf::app::FlightLoop::TakeSnapshot(']),
    ('hazard_loop', ['swf::app::FlightLoop::HazardMain()', 'swf::app::FlightLoop::RunHazard(']),
    ('hazard', ['swf::app::MapperHazardStage::Process(']),
]
FRAME_GROUP = ['loop', 'acquire', 'rectify', 'track', 'estimate', 'publish', 'map']
COMPARED = ['acquire', 'rectify', 'track', 'estimate', 'publish', 'map', 'hazard']
CHECK_TOLERANCE = 0.03
DEMO_FX_512 = 1154.7413769374866  # the demo rig's focal length at 512 px (25 deg field of view)
PERIOD_MS = 1000.0 / 15.0
HAZARD_EVERY = 5  # flight.cfg: a map every 5th frame, on its own core, due before the next
# Frame-time models: instructions / (IPC x clock). The IPCs are assumptions, not measurements
# (there is no such core here): a range for an in-order dual-issue A53 on this code (scalar
# double arithmetic, NEON image kernels, cache-missing image passes) and for an out-of-order A72.
CORES = [
    ('A53 @ 1.0 GHz', 1.0e9, 0.5, 0.8),
    ('A53 @ 0.8 GHz (HPSC-class cluster)', 0.8e9, 0.5, 0.8),
    ('A72 @ 1.5 GHz', 1.5e9, 1.2, 1.8),
]


def mangled_prefixes(binary, nm):
    """{stage: [mangled name]} of STAGES' functions in binary (nm's symbol table, demangled with
    c++filt to match)."""
    out = subprocess.run([nm, '--defined-only', binary], stdout=subprocess.PIPE, text=True,
                         check=True).stdout
    mangled = [line.split()[-1] for line in out.splitlines() if line.split()]
    demangled = subprocess.run(['c++filt'], input='\n'.join(mangled), stdout=subprocess.PIPE,
                               text=True, check=True).stdout.splitlines()
    found = {name: [] for name, _ in STAGES}
    for m, d in zip(mangled, demangled):
        for name, prefixes in STAGES:
            if any(d.startswith(p) for p in prefixes) and not re.search(r'\.(cold|part)', m):
                found[name].append(m)
    missing = [name for name, m in found.items() if not m]
    if missing:
        raise SystemExit('%s: no symbol for stage(s) %s' % (binary, ', '.join(missing)))
    return found


def plugin_counts(emulator, binary, nm, plugin, args, out):
    stages = mangled_prefixes(binary, nm)
    spec = ','.join(['out=' + out] + ['stage=%s:%s' % (name, m)
                                      for name, ms in stages.items() for m in ms])
    cross_isa.run('swf-fsw under %s with the stage counter' % os.path.basename(emulator[0]),
                  emulator + ['-plugin', plugin + ',' + spec, binary] + args)
    with open(out) as f:
        return json.load(f)['stages']


def callgrind_counts(binary, args, out):
    cross_isa.run('swf-fsw under callgrind',
                  ['valgrind', '--tool=callgrind', '--callgrind-out-file=' + out, binary] + args)
    text = subprocess.run(['callgrind_annotate', '--inclusive=yes', '--threshold=100', out],
                          stdout=subprocess.PIPE, text=True, check=True).stdout
    inclusive = {}
    for line in text.splitlines():
        m = re.match(r'\s*([\d,]+) \([^)]*\)\s+\S*?:(.*?)(?: \[[^\]]*\])?$', line)
        if m:
            inclusive[m.group(2)] = inclusive.get(m.group(2), 0) + int(m.group(1).replace(',', ''))
    counts = {}
    for name, prefixes in STAGES:
        counts[name] = sum(v for fn, v in inclusive.items()
                           if any(fn.startswith(p) for p in prefixes) and own(fn))
    # Inclusive costs nest: a stage's callees that are stages are taken out of it, as the plugin
    # counts them (Run includes Cycle, which includes the stages; HazardMain includes RunHazard).
    counts['loop'] -= sum(counts[s] for s in FRAME_GROUP if s != 'loop')
    counts['loop'] -= inclusive_of(inclusive, 'swf::app::FlightLoop::Cycle(')
    counts['hazard_loop'] -= counts['hazard'] + inclusive_of(
        inclusive, 'swf::app::FlightLoop::RunHazard(')
    return counts


def own(function):
    """False for the parts GCC split out of a function (clones: their cost is in the function's
    inclusive cost already) and for callgrind's recursion levels (name'2)."""
    return '[clone' not in function and "'" not in function


def inclusive_of(inclusive, prefix):
    return sum(v for fn, v in inclusive.items() if fn.startswith(prefix) and own(fn))


def write_calibration(path, side, width, height):
    """tests/cross_isa's calibration of the demo rig's camera (512x384) at width x height: the
    same 25 degree field of view, so the focal length and the centre scale with the size. A real
    camera's rectification is never the identity (which swf-fsw detects and skips): a radial
    distortion of 0.03 px at the corners makes it rectify every pixel as it would in flight."""
    with open(os.path.join(ROOT, 'tests', 'cross_isa', 'demo_%s.yaml' % side)) as f:
        text = f.read()
    fx = DEMO_FX_512 * width / 512.0
    text = text.replace('resolution: [512, 384]', 'resolution: [%d, %d]' % (width, height))
    text = re.sub(r'intrinsics: \[[^\]]*\]', 'intrinsics: [%r, %r, %r, %r]' %
                  (fx, fx, (width - 1) / 2.0, (height - 1) / 2.0), text)
    text = text.replace('distortion_coefficients: [0.0, 0.0, 0.0, 0.0]',
                        'distortion_coefficients: [-0.001, 0.0, 0.0, 0.0]')
    with open(path, 'w') as f:
        f.write(text)


def summary_memory(workdir, tag, size):
    with open(os.path.join(workdir, '%s_%s.json' % (tag, size))) as f:
        return json.load(f)['memory']


def per_frame(counts, frames, maps):
    frame_group = sum(counts[s] for s in FRAME_GROUP)
    out = {s: counts[s] / frames for s in FRAME_GROUP}
    out['frame_group'] = frame_group / frames
    out['hazard_per_map'] = counts['hazard'] / maps if maps else 0.0
    return out


def estimates(per):
    """Frame-group and hazard-map times (ms) on CORES, slow (low IPC) and fast."""
    out = []
    for name, clock, ipc_low, ipc_high in CORES:
        out.append({
            'core': name,
            'frame_group_ms': [per['frame_group'] / (ipc * clock) * 1e3
                               for ipc in (ipc_low, ipc_high)],
            'hazard_map_ms': [per['hazard_per_map'] / (ipc * clock) * 1e3
                              for ipc in (ipc_low, ipc_high)],
        })
    return out


def profile_size(args, width, height, workdir):
    size = '%dx%d' % (width, height)
    descent = os.path.join(workdir, 'descent_%s.lcmlog' % size)
    cross_isa.run('recording the descent at %s (host swf-sil, %d frames)' % (size, args.frames),
                  [args.sil, '--config', os.path.join(ROOT, 'fsw/app/config/demo.cfg'),
                   '--set', 'sim.frames: %d' % args.frames, '--set', 'sim.width_px: %d' % width,
                   '--set', 'sim.height_px: %d' % height, '--set', 'pacing: lockstep',
                   '--set', 'lcm.publish: false', '--set', 'rt.mlockall: false',
                   '--set', 'rt.priority: 0', '--set', 'record.path: ' + descent])
    camera = os.path.join(workdir, 'camera_%s.lcmlog' % size)
    frames = cross_isa.camera_log(descent, camera)
    calibrations = []
    for side in ('left', 'right'):
        calibrations.append(os.path.join(workdir, '%s_%s.yaml' % (side, size)))
        write_calibration(calibrations[-1], side, width, height)
    maps = len(range(HAZARD_EVERY - 1, frames, HAZARD_EVERY))

    def fsw_args(tag):
        return ['--config', os.path.join(ROOT, 'tests/cross_isa/flight.cfg'),
                '--set', 'log.path: ' + camera,
                '--set', 'camera.left_calibration: ' + calibrations[0],
                '--set', 'camera.right_calibration: ' + calibrations[1],
                '--set', 'summary.path: ' + os.path.join(workdir, '%s_%s.json' % (tag, size))]

    result = {'size': size, 'frames': frames, 'hazard_maps': maps}
    # Memory: the process's figures from a plain native run; the stacks also under the emulator
    # (the guest's stacks are the flight computer's; its resident memory would be the emulator's).
    # As in flight: memory locked (mlockall), so that the faults after start are the real ones.
    cross_isa.run('swf-fsw natively (memory figures)',
                  [args.fsw] + fsw_args('native') + ['--set', 'rt.mlockall: true'])
    result['memory'] = {'x86-64': summary_memory(workdir, 'native', size)}
    with open(os.path.join(workdir, 'native_%s.json' % size)) as f:
        result['mlockall'] = json.load(f)['mlockall']
    counts = {'x86-64 callgrind': callgrind_counts(
        args.fsw, fsw_args('callgrind'), os.path.join(workdir, 'callgrind_%s.out' % size))}
    counts['x86-64 plugin'] = plugin_counts(
        [shutil.which('qemu-x86_64') or 'qemu-x86_64'], args.fsw, 'nm', args.plugin,
        fsw_args('x86'), os.path.join(workdir, 'counts_x86_%s.json' % size))
    if args.target_fsw:
        counts['aarch64 plugin'] = plugin_counts(
            shlex.split(args.emulator), args.target_fsw, 'aarch64-linux-gnu-nm', args.plugin,
            fsw_args('aarch64'), os.path.join(workdir, 'counts_aarch64_%s.json' % size))
        result['memory']['aarch64 stacks'] = summary_memory(
            workdir, 'aarch64', size)['stack_high_water_bytes']
    result['instructions'] = counts
    result['per_frame'] = {k: per_frame(v, frames, maps) for k, v in counts.items()}
    flight = 'aarch64 plugin' if args.target_fsw else 'x86-64 callgrind'
    result['estimates_from'] = flight
    result['estimates'] = estimates(result['per_frame'][flight])
    return result


def agreement(result):
    """Problems found comparing the plugin's host counts with callgrind's (empty when none)."""
    problems = []
    cg, pl = result['instructions']['x86-64 callgrind'], result['instructions']['x86-64 plugin']
    for s in COMPARED:
        if cg[s] <= 0 or pl[s] <= 0:
            problems.append('%s: stage %s counted nothing (callgrind %d, plugin %d)' %
                            (result['size'], s, cg[s], pl[s]))
        elif abs(pl[s] - cg[s]) > CHECK_TOLERANCE * cg[s]:
            problems.append('%s: stage %s: plugin %d vs callgrind %d instructions (%.1f%%)' %
                            (result['size'], s, pl[s], cg[s], 100.0 * (pl[s] - cg[s]) / cg[s]))
    for name, counts in result['instructions'].items():
        if any(counts[s] <= 0 for s in COMPARED):
            problems.append('%s: %s counted nothing in a stage: %s' % (result['size'], name, counts))
    return problems


def print_table(result):
    print('\n%s, %d frames, %d hazard maps: instructions per frame (millions)' %
          (result['size'], result['frames'], result['hazard_maps']))
    columns = list(result['per_frame'])
    print('| stage | ' + ' | '.join(columns) + ' |')
    print('|---|' + '---:|' * len(columns))
    for s in FRAME_GROUP + ['frame_group', 'hazard_per_map']:
        print('| %s | ' % s + ' | '.join('%.2f' % (result['per_frame'][c][s] / 1e6)
                                        for c in columns) + ' |')
    m = result['memory']['x86-64']
    print('\nMemory (x86-64, native, mlockall %s): %.1f MiB resident at start, %.1f MiB at the end, peak %.1f '
          'MiB, %d minor and %d major page faults after start; stack high-water (bytes): %s' %
          (result['mlockall'], m['resident_bytes_at_start'] / 2**20, m['resident_bytes_at_end'] / 2**20,
           m['peak_resident_bytes'] / 2**20, m['minor_faults_after_start'],
           m['major_faults_after_start'], m['stack_high_water_bytes']))
    if 'aarch64 stacks' in result['memory']:
        print('Stack high-water on aarch64 (emulated; bytes): %s' %
              result['memory']['aarch64 stacks'])
    print('\nEstimated times from the %s counts (IPC range per core; 15 Hz period %.1f ms; a map '
          'is due within %d periods):' % (result['estimates_from'], PERIOD_MS, HAZARD_EVERY))
    for e in result['estimates']:
        print('- %s: frame group %.1f-%.1f ms, hazard map %.0f-%.0f ms' %
              (e['core'], e['frame_group_ms'][1], e['frame_group_ms'][0],
               e['hazard_map_ms'][1], e['hazard_map_ms'][0]))


def main():
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    p.add_argument('--sil', required=True)
    p.add_argument('--fsw', required=True, help="the host's swf-fsw")
    p.add_argument('--plugin', required=True, help='libswf_stage_count.so (host build)')
    p.add_argument('--target-fsw', help='the aarch64 swf-fsw')
    p.add_argument('--emulator', default='qemu-aarch64 -L /',
                   help='the plugin-capable emulator and its options, one string')
    p.add_argument('--frames', type=int, default=20)
    p.add_argument('--size', action='append', help='WxH (repeatable; default 512x384)')
    p.add_argument('--json', help='write the results here')
    p.add_argument('--check', action='store_true',
                   help='fail when the plugin and callgrind disagree on the host')
    p.add_argument('--keep', help='work in this directory and keep it')
    args = p.parse_args()
    workdir = args.keep or tempfile.mkdtemp(prefix='stage_profile.')
    os.makedirs(workdir, exist_ok=True)
    results, problems = [], []
    try:
        for size in args.size or ['512x384']:
            width, height = (int(v) for v in size.lower().split('x'))
            result = profile_size(args, width, height, workdir)
            results.append(result)
            print_table(result)
            problems += agreement(result)
    finally:
        if not args.keep:
            shutil.rmtree(workdir, ignore_errors=True)
    if args.json:
        with open(args.json, 'w') as f:
            json.dump({'results': results, 'agreement_problems': problems}, f, indent=1)
    for line in problems:
        print('DISAGREE: ' + line)
    if not problems:
        print('\nthe plugin and callgrind agree on every compared stage within %.0f%%' %
              (100 * CHECK_TOLERANCE))
    return 1 if (problems and args.check) else 0


if __name__ == '__main__':
    sys.exit(main())
