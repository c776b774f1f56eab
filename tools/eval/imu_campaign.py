#!/usr/bin/python3
"""The simulated descent of the demo (fsw/app/config/demo.cfg) over many seeds, flown by swf-sil
with four process inputs (and the MEMS unit with a looser start), to compare what the IMU brings:

  ideal      stereo with the demo's idealized motion input (the true relative motion plus white
             noise of 2 cm / 0.5 mrad per frame, sim.imu_sigma_*)
  stereo     stereo only: no motion input, the bounded constant-velocity model
  mems       stereo-inertial with the simulated ADIS16448 (sim.imu_unit: mems)
  tactical   stereo-inertial with the simulated HG1700 (sim.imu_unit: tactical)
  mems_loose the MEMS unit with the handover velocity's sigma at 0.1 m/s instead of the demo's
             0.01 m/s (imu.velocity_sigma_mps): what a less well known start costs

Each run's summary (swf-sil summary.path) gives the pose RMS error over the descent, the last
landmark map's RMS error, the position NEES of every output, the integrity counts, and for the
inertial runs the biases against the unit's truth and the RMS error of the unit alone from the
same start (IMU-only dead reckoning). Writes OUT/runs.json (every run) and OUT/summary.md.

Position NEES: for a consistent estimator e^T P^-1 e is chi-square with 3 degrees of freedom; its
mean over S independent seeds at one frame is chi-square(3 S) / S. The band is that
distribution's central 95 % (Wilson-Hilferty); a consistent estimator has about 95 % of the
frames inside it, an overconfident one lies above. The summary also gives that mean by tenths of
the descent, and the front end's error against the truth binned by the magnification of each
landmark since its template was taken, by track age and by altitude (swf-sil's
tracking_error_bins), in pixels and over the sigma the filter stated.

usage: imu_campaign.py --fsw SWF-FSW [--config demo.cfg] [--seeds 20] [--first-seed 1]
                       [--jobs 2] [--inputs mems,tactical] [--set "KEY: VALUE" ...] --out DIR
(--inputs: a subset of the inputs above; --set: a configuration override for every run, after
the input's own.)
Exit 0 when every run completed (whatever its numbers), 1 otherwise."""
import argparse
import concurrent.futures
import json
import math
import os
import statistics
import subprocess
import sys

INPUTS = {
    'ideal': ['imu.enabled: false', 'sim.imu: true'],
    'stereo': ['imu.enabled: false', 'sim.imu: false'],
    'mems': ['sim.imu_unit: mems', 'imu.enabled: true'],
    'tactical': ['sim.imu_unit: tactical', 'imu.enabled: true'],
    'mems_loose': ['sim.imu_unit: mems', 'imu.enabled: true', 'imu.velocity_sigma_mps: 0.1'],
}
LABELS = {
    'ideal': 'stereo + idealized motion input (today\'s demo)',
    'stereo': 'stereo only (constant velocity)',
    'mems': 'stereo-inertial, MEMS (ADIS16448)',
    'tactical': 'stereo-inertial, tactical (HG1700)',
    'mems_loose': 'stereo-inertial, MEMS, handover velocity stated to 0.1 m/s',
}


def run(fsw, config, out, seed, name, overrides=()):
    summary = os.path.join(out, 'seed%03d_%s.json' % (seed, name))
    cmd = [fsw, '--config', config, '--set', 'pacing: lockstep', '--set', 'lcm.publish: false',
           '--set', 'rt.mlockall: false', '--set', 'rt.priority: 0',
           '--set', 'sim.seed: %d' % seed, '--set', 'summary.path: %s' % summary]
    for s in list(INPUTS[name]) + list(overrides):
        cmd += ['--set', s]
    proc = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                          check=False)
    record = {'seed': seed, 'input': name, 'exit_code': proc.returncode}
    try:
        with open(summary) as f:
            record['summary'] = json.load(f)
    except (OSError, ValueError) as e:
        record['error'] = 'no summary (%s): %s' % (e, proc.stderr.strip()[-400:])
    return record


def chi2_quantile(p, k):
    """Wilson-Hilferty approximation of the chi-square quantile (k degrees of freedom)."""
    # Inverse normal CDF by bisection on erf (no scipy in the flight tree's ground tools).
    lo, hi = -10.0, 10.0
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if 0.5 * (1.0 + math.erf(mid / math.sqrt(2.0))) < p:
            lo = mid
        else:
            hi = mid
    z = 0.5 * (lo + hi)
    c = 2.0 / (9.0 * k)
    return k * (1.0 - c + z * math.sqrt(c)) ** 3


def huber_effective_sigma(component, k=3.5):
    """The standard deviation a measurement with this error distribution has under Huber weights
    with threshold k times it: the M-estimator's asymptotic variance E[psi(e)^2] / E[psi'(e)]^2
    (psi(e) = clamp(e, -c, c)), with c = k x the result, solved by fixed-point iteration. Taken
    over swf-sil's histogram of the signed error (bin centres; errors outside it at its edge).
    The sigma the filter should state for this front end: the information a Huber-weighted
    measurement really carries, tails included."""
    counts = component.get('counts') or []
    if not counts:
        return None
    width = 0.05
    first = -1.5
    centers = [first + width * (i + 0.5) for i in range(len(counts))]
    outside = component.get('outside_histogram', 0)
    edge = abs(first)
    sigma = component.get('robust_sigma') or 0.05
    for _ in range(100):
        c = k * sigma
        n = sum(counts) + outside
        psi2 = (sum(w * min(abs(x), c) ** 2 for x, w in zip(centers, counts)) +
                outside * min(edge, c) ** 2) / n
        inside = sum(w for x, w in zip(centers, counts) if abs(x) < c) / n
        if inside <= 0:
            return None
        sigma = 0.5 * sigma + 0.5 * math.sqrt(psi2) / inside
    return sigma


def describe(values):
    values = [v for v in values if v is not None and math.isfinite(v)]
    if not values:
        return 'no finite value'
    return 'median %.3g, mean %.3g, max %.3g' % (statistics.median(values),
                                                  statistics.fmean(values), max(values))


def image_sizes(records):
    """The image sizes the runs flew (swf-sil's summary), as text: '512 x 384'."""
    sizes = sorted({(r['summary'].get('image_width_px'), r['summary'].get('image_height_px'))
                    for r in records if 'summary' in r})
    return ', '.join('%s x %s' % wh for wh in sizes) or 'no run finished'


def summarize(records, seeds, names=tuple(INPUTS), config='fsw/app/config/demo.cfg',
              overrides=()):
    by_input = {name: [r for r in records if r['input'] == name] for name in names}
    lines = ['| input | runs ok | pose RMS (m) | landmark RMS (m) | mean position NEES | '
             'NEES band: frames inside | VALID / DEGRADED / INVALID frames | protection '
             'violations |', '|---|---|---|---|---|---|---|---|']
    lo = chi2_quantile(0.025, 3 * len(seeds)) / len(seeds)
    hi = chi2_quantile(0.975, 3 * len(seeds)) / len(seeds)
    table = {}
    for name, runs in by_input.items():
        good = [r['summary'] for r in runs if 'summary' in r]
        pose = [s.get('pose_rms_error_m') for s in good]
        landmark = [s.get('landmark_rms_error_m') for s in good]
        nees = [s.get('mean_position_nees') for s in good]
        # Per frame: the mean over seeds of the NEES, against the band.
        per_frame = [s.get('position_nees') or [] for s in good]
        frames = min((len(p) for p in per_frame), default=0)
        inside = 0
        counted = 0
        for k in range(1, frames):  # frame 0 is the given start
            vals = [p[k] for p in per_frame if p[k] is not None]
            if len(vals) != len(per_frame):
                continue
            counted += 1
            inside += lo <= statistics.fmean(vals) <= hi
        # The same mean by tenths of the descent (frames 1.. split in ten): where it drifts.
        tenths = []
        for t in range(10):
            ks = range(1 + t * (frames - 1) // 10, 1 + (t + 1) * (frames - 1) // 10)
            vals = [p[k] for p in per_frame for k in ks if p[k] is not None]
            tenths.append(statistics.fmean(vals) if vals else None)
        integrity = [s.get('integrity', {}) for s in good]
        valid = sum(i.get('frames_valid', 0) for i in integrity)
        degraded = sum(i.get('frames_degraded', 0) for i in integrity)
        invalid = sum(i.get('frames_invalid', 0) for i in integrity)
        violations = sum(i.get('protection_violations', 0) for i in integrity)
        ok = sum(1 for r in runs if r.get('exit_code') == 0)
        table[name] = {'pose_rms_m': pose, 'landmark_rms_m': landmark, 'mean_nees': nees,
                       'frames_in_band': inside, 'frames_counted': counted, 'tenths': tenths}
        lines.append('| %s | %d of %d (exit 0) | %s | %s | %s | %d of %d | %d / %d / %d | %d |' % (
            LABELS[name], ok, len(runs), describe(pose), describe(landmark), describe(nees),
            inside, counted, valid, degraded, invalid, violations))
    text = ['## Stereo-inertial descent campaign (`tools/eval/imu_campaign.py`)', '',
            'Seeds %d-%d of the descent of %s%s (%s px, lockstep), each flown by swf-sil with '
            'the process inputs below. NEES band (95 %%, mean over %d seeds at a frame): '
            '[%.2f, %.2f].' % (
                seeds[0], seeds[-1], config,
                ''.join(' with `%s`' % o for o in overrides), image_sizes(records), len(seeds),
                lo, hi), ''] + lines + ['']
    for name in by_input:
        text.append('- %s: mean position NEES over the seeds by tenths of the descent (first to '
                    'last): %s.' % (LABELS[name], ' '.join(
                        '%.2f' % v if v is not None else '-' for v in table[name]['tenths'])))
    # The front end's error by magnification of the template's warp, track age and altitude
    # (swf-sil's tracking_error_bins): Huber-effective sigma in pixels, and of the errors divided
    # by the sigma the filter stated (1 where the measurement model fits), median over the runs.
    for name, runs in by_input.items():
        bins = [r['summary'].get('tracking_error_bins') for r in runs if 'summary' in r]
        bins = [b for b in bins if b]
        if not bins:
            continue
        for key in ('by_magnification', 'by_age', 'by_altitude_m'):
            cells = []
            for i, cell in enumerate(bins[0][key]):
                px = [b[key][i]['huber_sigma_px'] for b in bins
                      if b[key][i]['huber_sigma_px'] is not None]
                nz = [b[key][i]['normalized_huber_sigma'] for b in bins
                      if b[key][i]['normalized_huber_sigma'] is not None]
                if not px:
                    continue
                cells.append('[%g, %g): %.3f px, %.2f' % (
                    cell['from'], cell['to'], statistics.median(px),
                    statistics.median(nz) if nz else float('nan')))
            text.append('- %s, tracking error %s (Huber sigma, normalized): %s.' % (
                LABELS[name], key.replace('by_', 'by '), '; '.join(cells)))
    for unit in [u for u in ('mems', 'tactical', 'mems_loose') if u in by_input]:
        good = [r['summary'] for r in by_input[unit] if 'summary' in r]
        dr = [s.get('imu', {}).get('imu_only_pose_rms_error_m') for s in good]
        gyro = [s.get('imu', {}).get('gyro_bias_error_radps') for s in good]
        accel = [s.get('imu', {}).get('accel_bias_error_mps2') for s in good]
        text.append('- %s: the unit alone (IMU-only dead reckoning from the same start, biases '
                    'unknown) pose RMS %s m; biases at the end against the truth: gyroscope '
                    'error %s rad/s, accelerometer error %s m/s^2.' % (
                        LABELS[unit], describe(dr), describe(gyro), describe(accel)))
    # The front end's error against the renderer's truth (swf-sil's tracking_error_px: every
    # fused measurement of a known landmark against the true projection of the point its first
    # sighting defines), per run: the robust sigma (1.4826 x the median absolute deviation) and
    # the standard deviation of the signed u and v errors. What measurement_sigma_px states.
    for name, runs in by_input.items():
        signed = [r['summary'].get('tracking_error_px', {}).get('signed', {})
                  for r in runs if 'summary' in r]
        robust = [c.get('robust_sigma') for sg in signed for c in (sg.get('u', {}), sg.get('v', {}))]
        std = [c.get('std') for sg in signed for c in (sg.get('u', {}), sg.get('v', {}))]
        huber = [huber_effective_sigma(c) for sg in signed
                 for c in (sg.get('u', {}), sg.get('v', {}))]
        if any(v is not None for v in robust):
            text.append('- %s: front-end error against the truth (signed u and v, per run): robust '
                        'sigma %s px; standard deviation %s px; under Huber weights (3.5 sigma) '
                        'worth a Gaussian of %s px.' % (
                            LABELS[name], describe(robust), describe(std), describe(huber)))
    ideal = table['ideal']['pose_rms_m'] if 'ideal' in table else []
    mems = table['mems']['pose_rms_m'] if 'mems' in table else []
    pairs = [(m, i) for m, i in zip(mems, ideal) if m is not None and i is not None]
    if pairs:
        better = sum(1 for m, i in pairs if m <= i)
        text.append('- MEMS stereo-inertial against the idealized input, seed by seed: as accurate '
                    'or better (pose RMS) on %d of %d seeds; median ratio %.2f.' % (
                        better, len(pairs), statistics.median(m / i for m, i in pairs)))
    return '\n'.join(text) + '\n'


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--fsw', required=True)
    ap.add_argument('--config', default='fsw/app/config/demo.cfg')
    ap.add_argument('--seeds', type=int, default=20)
    ap.add_argument('--first-seed', type=int, default=1)
    ap.add_argument('--jobs', type=int, default=2)
    ap.add_argument('--inputs', default=','.join(INPUTS),
                    help='comma-separated subset of: ' + ', '.join(INPUTS))
    ap.add_argument('--set', action='append', default=[], metavar='"KEY: VALUE"',
                    help='a configuration override for every run (repeatable)')
    ap.add_argument('--out', required=True)
    a = ap.parse_args()
    if a.seeds < 1 or a.jobs < 1:
        ap.error('--seeds and --jobs must be at least 1')
    names = [n for n in a.inputs.split(',') if n]
    unknown = [n for n in names if n not in INPUTS]
    if unknown or not names:
        ap.error('--inputs: unknown input(s) %s (known: %s)' % (', '.join(unknown) or '(none)',
                                                                ', '.join(INPUTS)))
    os.makedirs(a.out, exist_ok=True)
    seeds = list(range(a.first_seed, a.first_seed + a.seeds))
    with concurrent.futures.ThreadPoolExecutor(max_workers=a.jobs) as pool:
        futures = [pool.submit(run, a.fsw, a.config, a.out, s, n, a.set)
                   for s in seeds for n in names]
        records = [f.result() for f in futures]
    with open(os.path.join(a.out, 'runs.json'), 'w') as f:
        json.dump(records, f, indent=1, allow_nan=False, default=str)
    text = summarize(records, seeds, names, a.config, a.set)
    with open(os.path.join(a.out, 'summary.md'), 'w') as f:
        f.write(text)
    sys.stdout.write(text)
    failed = [r for r in records if 'summary' not in r]
    for r in failed:
        sys.stderr.write('seed %d %s: %s\n' % (r['seed'], r['input'], r['error']))
    return 1 if failed else 0


if __name__ == '__main__':
    sys.exit(main())
