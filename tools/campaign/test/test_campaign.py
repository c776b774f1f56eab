"""The campaign tool against the real swf-sil ($SWF_SIL): spec errors, run seeds, the local engine
and its faults (a killed run, a missing binary, a full disk, another campaign's directory),
resumption and the report."""
import json
import os
import shutil
import stat
import subprocess
import sys
import tempfile
import textwrap
import time
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
TOOL = os.path.join(HERE, '..', 'swf_campaign.py')
DEMO_CFG = os.path.abspath(os.path.join(HERE, '..', '..', '..', 'fsw', 'app', 'config',
                                        'demo.cfg'))
TINY = os.path.join(HERE, 'tiny.yaml')
SIL = os.environ.get('SWF_SIL', '')
sys.path.insert(0, os.path.join(HERE, '..'))
from swfcampaign import report as reportmod  # noqa: E402
from swfcampaign import spec as specmod  # noqa: E402


def campaign(*args, sil=None, env=None):
    cmd = ['/usr/bin/python3', TOOL] + list(args) + ['--sil', sil or SIL]
    return subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                          check=False, env=env)


def read_json(path):
    with open(path, encoding='utf-8') as f:
        return json.load(f)


def write_wrapper(path, body):
    """An swf-sil stand-in: runs `body` (sh) and then the real swf-sil with the same arguments."""
    with open(path, 'w', encoding='utf-8') as f:
        f.write('#!/bin/sh\n%s\nexec "%s" "$@"\n' % (body, SIL))
    os.chmod(path, os.stat(path).st_mode | stat.S_IXUSR)


class SpecErrors(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp()
        self.addCleanup(shutil.rmtree, self.dir)

    def error(self, body):
        path = os.path.join(self.dir, 'spec.yaml')
        with open(path, 'w', encoding='utf-8') as f:
            f.write(textwrap.dedent(body).replace('CONFIG', DEMO_CFG))
        with self.assertRaises(specmod.SpecError) as ctx:
            specmod.load(path)
        return str(ctx.exception).replace(path, 'spec.yaml')

    HEAD = 'name: t\nseed: 1\nruns: 4\nconfig: CONFIG\n'

    def test_each_problem_names_file_line_and_field(self):
        cases = [
            ('name: t\nseed: 1\nruns: -1\nconfig: CONFIG\n',
             'spec.yaml:3: runs: expected an integer in [1, 100000], got -1'),
            (self.HEAD + 'dispersion:\n  sim.seed: run_seed\n',
             'spec.yaml:5: dispersion: unknown field'),
            ('name: t\nseed: 1\nconfig: CONFIG\n', 'spec.yaml:1: runs: missing'),
            (self.HEAD + 'dispersions:\n  sim.hfov_deg: {normal: [25]}\n',
             'spec.yaml:6: dispersions.sim.hfov_deg.normal: expected [mean, sigma]'),
            (self.HEAD + 'dispersions:\n  sim.hfov_deg: {uniform: [30, 20]}\n',
             'spec.yaml:6: dispersions.sim.hfov_deg.uniform: low above high'),
            (self.HEAD + 'dispersions:\n  sim.hfov_deg: {normal: [25, -1]}\n',
             'spec.yaml:6: dispersions.sim.hfov_deg.normal: a negative sigma'),
            (self.HEAD + 'dispersions:\n  x.y: {normal: [[0, 0], [1, 1, 1]]}\n',
             'spec.yaml:6: dispersions.x.y.normal: the two vectors differ in length'),
            (self.HEAD + 'dispersions:\n  sim.terrain: {choice: [rocks], weights: [1, 2]}\n',
             'spec.yaml:6: dispersions.sim.terrain.weights: one non-negative weight per choice'),
            (self.HEAD + 'dispersions:\n  sim.hfov_deg: {normal: [25, 1], spread: 2}\n',
             'spec.yaml:6: dispersions.sim.hfov_deg.spread: unknown field'),
            (self.HEAD + 'dispersions:\n  sim.hfov_deg: {normal: [25, 1], uniform: [1, 2]}\n',
             'spec.yaml:6: dispersions.sim.hfov_deg: give exactly one of normal, uniform, choice'),
            (self.HEAD + 'fixed:\n  pacing: realtime\n',
             'spec.yaml:6: fixed.pacing: set by the campaign itself'),
            (self.HEAD + 'fixed:\n  sim.frames: 3\ndispersions:\n  sim.frames: {uniform: [1, 2]}\n',
             'spec.yaml:8: dispersions.sim.frames: given twice'),
            (self.HEAD + 'fixed:\n  Sim Frames: 3\n',
             'spec.yaml:6: fixed.Sim Frames: not a swf-sil config key'),
            ('name: t\nseed: 1\nruns: 4\nconfig: nowhere.cfg\n',
             'spec.yaml:4: config: no such file'),
            (self.HEAD + 'fixed: [\n', 'spec.yaml:6: (syntax)'),
            (self.HEAD + 'dispersions:\n  sim.hfov_deg: {normal: [25, .inf]}\n',
             'spec.yaml:6: dispersions.sim.hfov_deg.normal: expected a finite number'),
        ]
        for body, expected in cases:
            with self.subTest(expected=expected):
                self.assertTrue(self.error(body).startswith(expected), self.error(body))

    def refused_by_swf_sil(self, dispersions):
        """The campaign's stderr for a spec with these dispersions, which must be refused
        (exit 2) before anything is written."""
        path = os.path.join(self.dir, 'spec.yaml')
        with open(path, 'w', encoding='utf-8') as f:
            f.write(self.HEAD.replace('CONFIG', DEMO_CFG) + 'dispersions:\n' + dispersions)
        r = campaign('run', path, '--out', os.path.join(self.dir, 'out'))
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertFalse(os.path.exists(os.path.join(self.dir, 'out')))
        return r.stderr.replace(path, 'spec.yaml')

    def test_unknown_config_key_is_refused_by_swf_sil_at_its_line(self):
        self.assertIn('spec.yaml:7: sim.wobble_m: swf-sil refuses it', self.refused_by_swf_sil(
            '  sim.seed: run_seed\n  sim.wobble_m: {uniform: [0, 1]}\n'))

    def test_a_value_swf_sil_refuses_at_the_distribution_edge(self):
        self.assertIn('spec.yaml:6: dispersions.sim.hfov_deg: swf-sil refuses 171.0',
                      self.refused_by_swf_sil('  sim.hfov_deg: {uniform: [20, 171]}\n'))


class Seeds(unittest.TestCase):
    def test_a_run_does_not_depend_on_the_campaign_size(self):
        small = specmod.load(TINY)
        big = specmod.load(TINY)
        big.runs = 500
        for i in range(small.runs):
            self.assertEqual(specmod.overrides(small, i), specmod.overrides(big, i))
        seeds = {specmod.run_seed(small.seed, i) for i in range(500)}
        self.assertEqual(len(seeds), 500)
        self.assertNotEqual(specmod.overrides(small, 0), specmod.overrides(small, 1))

    def test_draws_follow_the_distributions(self):
        s = specmod.load(TINY)
        s.dispersions = {'a': specmod.Dispersion('normal', ([10.0, 0.0], [2.0, 0.0])),
                         'b': specmod.Dispersion('uniform', ([1.0], [3.0]), hi=2.0),
                         'c': specmod.Dispersion('choice', ['x', 'y'], weights=[1, 0])}
        a = []
        for i in range(2000):
            o = specmod.overrides(s, i)
            x, zero = (float(v) for v in o['a'].split(','))
            a.append(x)
            self.assertEqual(zero, 0.0)
            self.assertTrue(1.0 <= float(o['b']) <= 2.0)
            self.assertEqual(o['c'], 'x')
        mean = sum(a) / len(a)
        sd = (sum((x - mean) ** 2 for x in a) / len(a)) ** 0.5
        self.assertAlmostEqual(mean, 10.0, delta=0.15)
        self.assertAlmostEqual(sd, 2.0, delta=0.15)


class Statistics(unittest.TestCase):
    def test_percentiles_interpolate_between_ranks(self):
        self.assertEqual(reportmod.percentile([3.0, 1.0, 2.0, 4.0], 50), 2.5)
        self.assertEqual(reportmod.percentile([1.0, 2.0], 100), 2.0)
        self.assertIsNone(reportmod.percentile([float('nan'), None], 50))

    def test_rank_correlation(self):
        self.assertAlmostEqual(reportmod.spearman([1, 2, 3, 4], [10, 20, 30, 45]), 1.0)
        self.assertAlmostEqual(reportmod.spearman([1, 2, 3, 4], [9, 7, 5, 1]), -1.0)
        self.assertEqual(reportmod.ranks([5, 1, 5, 2]), [3.5, 1.0, 3.5, 2.0])
        self.assertIsNone(reportmod.spearman([1, 1, 1], [1, 2, 3]))

    def test_altitude_bins_are_round(self):
        self.assertEqual(reportmod.altitude_bins(95.0)[:3], [0.0, 10.0, 20.0])
        self.assertEqual(reportmod.altitude_bins(95.0)[-1], 100.0)
        self.assertEqual(reportmod.altitude_bins(9.0)[-1], 9.0)


class LocalEngine(unittest.TestCase):
    def setUp(self):
        self.assertTrue(os.access(SIL, os.X_OK), 'SWF_SIL must name the swf-sil binary')
        self.dir = tempfile.mkdtemp()
        self.addCleanup(shutil.rmtree, self.dir)
        self.out = os.path.join(self.dir, 'tiny')

    def test_a_killed_run_is_listed_kept_and_flown_again_alone(self):
        killer = os.path.join(self.dir, 'sil-killed-at-run-2')
        write_wrapper(killer, 'case "$*" in *runs/00002/summary.json*) kill -KILL $$ ;; esac')
        r = campaign('run', TINY, '--out', self.out, '--jobs', '2', sil=killer)
        self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
        self.assertIn('run 2: killed by signal 9 (SIGKILL)', r.stderr)
        report = read_json(os.path.join(self.out, 'report', 'report.json'))
        self.assertEqual(report['completed'], 5)
        [lost] = report['not_completed']
        self.assertEqual((lost['run'], lost['signal']), (2, 9))
        run2 = os.path.join(self.out, 'runs', '00002')
        self.assertTrue(os.path.exists(os.path.join(run2, 'run.json')))  # its inputs are kept
        before = {i: os.stat(os.path.join(self.out, 'runs', '%05d' % i, 'status.json')).st_mtime_ns
                  for i in (0, 1, 3, 4, 5)}

        r = campaign('run', TINY, '--out', self.out, '--jobs', '2')
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertIn('6 runs, 5 done, 1 to fly', r.stdout)
        for i, t in before.items():
            self.assertEqual(os.stat(os.path.join(self.out, 'runs', '%05d' % i,
                                                  'status.json')).st_mtime_ns, t)
        report = read_json(os.path.join(self.out, 'report', 'report.json'))
        self.assertEqual((report['completed'], report['not_completed']), (6, []))
        self.check_report(report)

        # Any run alone, with its log, gives the same summary.
        r = campaign('reproduce', self.out, '4')
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertIn('summary identical to', r.stdout)
        self.assertTrue(os.path.getsize(os.path.join(self.out, 'runs', '00004', 'reproduce',
                                                     'descent.lcmlog')) > 0)

    def test_a_killed_campaign_resumes_where_it_stopped(self):
        # Run 3 hangs, so the campaign is surely mid-run when it is killed, however loaded the
        # machine is.
        stalling = os.path.join(self.dir, 'sil-stalls-at-run-3')
        write_wrapper(stalling, 'case "$*" in *runs/00003/summary.json*) sleep 60 ;; esac')
        proc = subprocess.Popen(['/usr/bin/python3', TOOL, 'run', TINY, '--out', self.out,
                                 '--jobs', '1', '--sil', stalling], stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)
        third = os.path.join(self.out, 'runs', '00002', 'status.json')
        for _ in range(1200):
            if os.path.exists(third) or proc.poll() is not None:
                break
            time.sleep(0.1)
        proc.kill()  # SIGKILL: no cleanup; the run in flight dies with it
        proc.wait()
        done = sum(os.path.exists(os.path.join(self.out, 'runs', '%05d' % i, 'status.json'))
                   for i in range(6))
        self.assertEqual(done, 3)
        r = campaign('run', TINY, '--out', self.out, '--jobs', '2', '--no-refly')
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertIn('6 runs, 3 done, 3 to fly', r.stdout)
        self.assertEqual(read_json(os.path.join(self.out, 'report', 'report.json'))['completed'],
                         6)

        # A Python without matplotlib still writes the report, and says which plots are missing.
        blocker = os.path.join(self.dir, 'no_matplotlib', 'matplotlib')
        os.makedirs(blocker)
        with open(os.path.join(blocker, '__init__.py'), 'w', encoding='utf-8') as f:
            f.write("raise ImportError('No module named matplotlib')\n")
        env = dict(os.environ, PYTHONPATH=os.path.dirname(blocker))
        r = campaign('report', self.out, '--no-refly', env=env)
        self.assertEqual(r.returncode, 1, r.stdout + r.stderr)  # a report short of its plots
        self.assertNotIn('Traceback', r.stderr)
        self.assertIn('plots: the campaign plots were not drawn: No module named matplotlib',
                      r.stderr)
        report = read_json(os.path.join(self.out, 'report', 'report.json'))
        self.assertEqual(report['completed'], 6)
        self.assertEqual(len(report['plot_errors']), 1)
        with open(os.path.join(self.out, 'report', 'report.md'), encoding='utf-8') as f:
            self.assertIn('## Plots not drawn', f.read())

    def check_report(self, report):
        nav = report['navigation']
        self.assertEqual(nav['final_position_error_m']['n'], 6)
        self.assertGreater(nav['final_position_error_m']['max'], 0.0)
        self.assertLess(nav['final_position_error_m']['p50'], 1.0)
        self.assertGreater(sum(b['position_error_m']['n'] for b in nav['by_altitude']), 6 * 11)
        self.assertGreater(report['consistency']['outputs_with_covariance'], 0)
        self.assertGreater(report['hazard']['maps'], 0)
        self.assertIn('estimate', report['timing']['stages'])
        worst = report['worst_runs'][0]
        self.assertEqual(report['worst_reproduced'], {str(worst['run']): True})
        self.assertTrue(os.path.getsize(os.path.join(
            self.out, 'runs', '%05d' % worst['run'], 'reproduce', 'descent.lcmlog')) > 0)
        with open(os.path.join(self.out, 'report', 'report.md'), encoding='utf-8') as f:
            md = f.read()
        self.assertIn('tools/campaign/swf_campaign.py reproduce %s %d' % (self.out, worst['run']),
                      md)
        for png in ('final_error_cdf.png', 'error_by_altitude.png', 'attitude_by_altitude.png',
                    'nees_by_altitude.png', 'hazard_by_altitude.png', 'stage_times.png'):
            with open(os.path.join(self.out, 'report', png), 'rb') as f:
                self.assertEqual(f.read(8), b'\x89PNG\r\n\x1a\n', png)
            self.assertIn('](%s)' % png, md)
        # The worst run's own plots, drawn by swf-plot from the log its re-flight kept.
        for png in ('trajectory.png', 'attitude_error.png', 'landmark_error.png', 'map.png',
                    'hazard.png'):
            path = 'run_%05d/%s' % (worst['run'], png)
            with open(os.path.join(self.out, 'report', path), 'rb') as f:
                self.assertEqual(f.read(8), b'\x89PNG\r\n\x1a\n', path)
            self.assertIn('](%s)' % path, md)

    def test_a_missing_binary_is_refused_before_anything_is_written(self):
        r = campaign('run', TINY, '--out', self.out, sil=os.path.join(self.dir, 'no-swf-sil'))
        self.assertEqual(r.returncode, 2)
        self.assertIn('swf-sil not found or not executable', r.stderr)
        self.assertFalse(os.path.exists(self.out))

    def test_a_directory_of_another_campaign_is_refused(self):
        other = os.path.join(self.dir, 'other.yaml')
        with open(TINY) as f, open(other, 'w') as g:
            g.write(f.read().replace('runs: 6', 'runs: 1').replace(
                '../../../fsw', os.path.join(HERE, '..', '..', '..', 'fsw')))
        r = campaign('run', other, '--out', self.out, '--no-refly')
        self.assertEqual(r.returncode, 0, r.stderr)
        r = campaign('run', TINY, '--out', self.out)
        self.assertEqual(r.returncode, 2)
        self.assertIn('holds another campaign', r.stderr)

    def test_a_full_disk_fails_runs_clearly_and_resumes(self):
        self.assertEqual(os.geteuid(), 0, 'a private tmpfs needs root (unshare --mount)')
        # A private tmpfs; the stand-in fills it when run 3 starts (another process eating the
        # disk mid-campaign), then the space comes back and the same command resumes.
        disk = os.path.join(self.dir, 'disk')
        os.makedirs(disk)
        filler = os.path.join(disk, 'filler')
        eater = os.path.join(self.dir, 'sil-disk-full-from-run-3')
        write_wrapper(eater, 'case "$*" in *runs/00003/summary.json*) '
                      'dd if=/dev/zero of=%s bs=1M 2>/dev/null ;; esac' % filler)
        out = os.path.join(disk, 'tiny')
        script = textwrap.dedent('''\
            set -u
            mount -t tmpfs -o size=48m tmpfs {disk} || exit 99
            /usr/bin/python3 {tool} run {spec} --out {out} --jobs 1 --no-refly --sil {eater} \\
              > {d}/first.out 2> {d}/first.err
            echo $? > {d}/first.rc
            ls {out}/runs > {d}/first.runs
            rm -f {filler}
            /usr/bin/python3 {tool} run {spec} --out {out} --jobs 1 --no-refly --sil {sil} \\
              > {d}/second.out 2> {d}/second.err
            echo $? > {d}/second.rc
            cp {out}/report/report.json {d}/report.json
            ''').format(disk=disk, tool=TOOL, spec=TINY, out=out, eater=eater, d=self.dir,
                        filler=filler, sil=SIL)
        r = subprocess.run(['unshare', '--mount', '--propagation', 'private', 'sh', '-c', script],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, check=False)
        self.assertEqual(r.returncode, 0, r.stderr)

        def read(name):
            with open(os.path.join(self.dir, name)) as f:
                return f.read()
        self.assertEqual(read('first.rc').strip(), '1', read('first.err'))
        self.assertIn('No space left on device', read('first.err'))
        self.assertIn('6 runs, 3 done, 3 to fly', read('second.out'))
        self.assertEqual(read('second.rc').strip(), '0', read('second.err'))
        report = json.loads(read('report.json'))
        self.assertEqual(report['completed'], 6)


if __name__ == '__main__':
    unittest.main()
