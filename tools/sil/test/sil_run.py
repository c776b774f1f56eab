"""One swf-sil run of the demo configuration for the tests in this folder: lockstep, nothing
published, no real-time privileges, the given `--set` overrides; returns the run's summary and
ends the test when swf-sil fails or its verdict is not ok."""
import json
import os
import subprocess
import sys

# The constant 0.12 px measurement sigma of before the per-track sigma (no magnification or
# disparity terms), each sighting stated alone: `--set` overrides for fly().
CONSTANT_SIGMA = ('measurement_sigma_px: 0.12', 'measurement_sigma_per_magnification_px: 0',
                  'measurement_sigma_per_magnification_rad: 0',
                  'measurement_disparity_sigma_px: 0',
                  'measurement_disparity_sigma_per_parallax_px: 0',
                  'measurement_track_error: independent')


def fly(sil, cfg, workdir, name, *settings):
    summary = os.path.join(workdir, name + '.json')
    cmd = [sil, '--config', cfg, '--set', 'pacing: lockstep', '--set', 'lcm.publish: false',
           '--set', 'rt.mlockall: false', '--set', 'rt.priority: 0',
           '--set', 'summary.path: ' + summary]
    for s in settings:
        cmd += ['--set', s]
    run = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if run.returncode != 0:
        sys.stderr.write(run.stderr)
        raise SystemExit('%s: swf-sil exited %d: %s' % (name, run.returncode, ' '.join(cmd)))
    with open(summary) as f:
        s = json.load(f)
    if s['result'] != 'ok':
        raise SystemExit('%s: verdict %s, not ok' % (name, s['result']))
    return s
