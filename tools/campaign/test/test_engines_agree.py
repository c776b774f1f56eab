"""The same campaign through the local engine and through Slurm (a one-node cluster this test
starts on localhost and stops again) gives identical run summaries apart from the measured
times, and the same report apart from its timing section."""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
TOOL = os.path.join(HERE, '..', 'swf_campaign.py')
CLUSTER = os.path.join(HERE, 'slurm_cluster.sh')
SIL = os.environ.get('SWF_SIL', '')
# More runs than either engine runs at once (2), so each engine queues and the array job has
# several tasks; each run is about a second of one core.
RUNS = 8
sys.path.insert(0, os.path.join(HERE, '..'))
from swfcampaign import engine  # noqa: E402


def read_json(path):
    with open(path, encoding='utf-8') as f:
        return json.load(f)


class EnginesAgree(unittest.TestCase):
    def setUp(self):
        self.assertTrue(os.access(SIL, os.X_OK), 'SWF_SIL must name the swf-sil binary')
        self.dir = tempfile.mkdtemp(dir=os.environ.get('TMPDIR', '/tmp'))
        os.chmod(self.dir, 0o755)
        self.addCleanup(shutil.rmtree, self.dir, True)
        with open(os.path.join(HERE, 'tiny.yaml')) as f:
            text = f.read()
        self.spec = os.path.join(HERE, 'tiny8.yaml.tmp')
        with open(self.spec, 'w') as f:
            f.write(text.replace('name: tiny', 'name: tiny8').replace('runs: 6', 'runs: %d' % RUNS))
        self.addCleanup(os.remove, self.spec)

    def fly(self, out, engine, env):
        r = subprocess.run(['/usr/bin/python3', TOOL, 'run', self.spec, '--out', out,
                            '--engine', engine, '--sil', SIL, '--jobs', '2'],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                           check=False, timeout=500)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        return r

    def test_local_and_slurm_give_the_same_runs_and_report(self):
        local = os.path.join(self.dir, 'local')
        slurm = os.path.join(self.dir, 'slurm')
        self.fly(local, 'local', dict(os.environ))
        cluster = os.path.join(self.dir, 'cluster')
        os.makedirs(cluster)
        up = subprocess.run([CLUSTER, 'start', cluster], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, check=False)
        self.addCleanup(subprocess.run, [CLUSTER, 'stop', cluster], check=False)
        self.assertEqual(up.returncode, 0, up.stdout)
        r = self.fly(slurm, 'slurm', dict(os.environ, SLURM_CONF=os.path.join(cluster,
                                                                              'slurm.conf')))
        self.assertIn('submitted array job', r.stdout)
        for i in range(RUNS):
            a = read_json(os.path.join(local, 'runs', '%05d' % i, 'summary.json'))
            b = read_json(os.path.join(slurm, 'runs', '%05d' % i, 'summary.json'))
            self.assertEqual(a['result'], b['result'])
            self.assertEqual(engine.deterministic(a), engine.deterministic(b),
                             'run %d differs between the engines' % i)
        # Every slurm run was flown by a Slurm task, not by this process.
        logs = os.listdir(os.path.join(slurm, 'slurm'))
        self.assertEqual(len([n for n in logs if n.endswith('.out')]), RUNS)

        def report(out):
            with open(os.path.join(out, 'report', 'report.json')) as f:
                text = f.read().replace(out, 'OUT')
            r = json.loads(text)
            r.pop('timing')
            return r
        self.assertEqual(report(local), report(slurm))
        self.assertEqual(report(local)['completed'], RUNS)


if __name__ == '__main__':
    unittest.main()
