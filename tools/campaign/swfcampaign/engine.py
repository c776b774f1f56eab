"""Flying a campaign's runs: the campaign directory, one run, and the two engines.

    OUT/campaign.json   what the directory holds: name, digest of spec + nominal config, runs
    OUT/spec.yaml       the spec, copied (the directory is self-contained: workers and
    OUT/nominal.cfg     `reproduce` read these, not the originals)
    OUT/runs/NNNNN/     one run: run.json (seed, overrides, command) first, then stderr.txt,
                        summary.json (swf-sil), descent.lcmlog (kept when the run failed or
                        crashed) and status.json last, written atomically

A run is done when its status.json says completed: swf-sil wrote a whole summary and exited with
the code of the verdict in it (0 ok, 3 degraded, 1 failed). Anything else (killed, crashed,
refused, timed out, a write that failed) is not done, and a rerun of the campaign flies it again;
done runs are never flown twice.
"""
import json
import os
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

from . import spec as specmod

VERDICT_EXIT = {'ok': 0, 'degraded': 3, 'failed': 1}
# The settings of every campaign run: lockstep (deterministic, no frame left behind), no LCM
# traffic, no real-time privileges.
CAMPAIGN_SETS = [('pacing', 'lockstep'), ('lcm.publish', 'false'), ('rt.mlockall', 'false'),
                 ('rt.priority', '0')]
LOG_NAME = 'descent.lcmlog'
# Summary fields measured on the machine (times, memory use), not results: they differ between
# any two flights. 'run' echoes the command line (its output paths differ between a run and its
# reproduction), not a result either.
TIMING_KEYS = ('stages', 'mlockall', 'sched_fifo', 'overruns', 'hazard_overruns',
               'lockstep_waits', 'memory', 'run')


class CampaignError(Exception):
    """A problem that stops the campaign, with its message."""


def run_dir(out, index):
    return os.path.join(out, 'runs', '%05d' % index)


def write_atomically(path, text):
    tmp = path + '.tmp'
    with open(tmp, 'w', encoding='utf-8') as f:
        f.write(text)
    os.replace(tmp, path)


def read_json(path):
    try:
        with open(path, encoding='utf-8') as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def sil_command(sil, out, index, overrides, summary, record):
    cmd = [sil, '--config', os.path.join(out, 'nominal.cfg')]
    sets = list(CAMPAIGN_SETS) + [('summary.path', summary), ('record.path', record)]
    sets += sorted(overrides.items())
    for key, value in sets:
        cmd += ['--set', '%s: %s' % (key, value)]
    return cmd


def check_sil(sil):
    if not (os.path.isfile(sil) and os.access(sil, os.X_OK)):
        raise CampaignError('swf-sil not found or not executable: %s (build it: cmake --build '
                            '--preset release --target swf-sil, or pass --sil)' % sil)


def check_against_sil(spec, sil):
    """swf-sil --check on run 0 and on every dispersion's edge values: a key swf-sil does not know
    or a value it refuses is a spec error at that key's line."""
    def refused(sets):
        cmd = [sil, '--check', '--config', spec.config]
        for key, value in list(CAMPAIGN_SETS) + sorted(sets.items()):
            cmd += ['--set', '%s: %s' % (key, value)]
        proc = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                              check=False)
        return None if proc.returncode == 0 else (proc.stderr.strip() or
                                                  'swf-sil --check exited %d' % proc.returncode)

    def blame(message, keys):
        for key in keys:
            if key in message:
                return '%s:%d: %s: swf-sil refuses it: %s' % (spec.path, spec.lines[key], key,
                                                              message)
        return '%s: swf-sil refuses the configuration: %s' % (spec.path, message)

    base = specmod.overrides(spec, 0)
    problem = refused(base)
    if problem:
        raise specmod.SpecError(blame(problem, sorted(base, key=len, reverse=True)))
    for key, dispersion in sorted(spec.dispersions.items()):
        for value in dispersion.extremes():
            problem = refused(dict(base, **{key: value}))
            if problem:
                raise specmod.SpecError('%s:%d: dispersions.%s: swf-sil refuses %s: %s' % (
                    spec.path, spec.lines[key], key, value, problem))


def prepare(spec, out):
    """Creates OUT (or checks that it holds this same campaign) and copies spec and config."""
    digest = spec.digest()
    meta_path = os.path.join(out, 'campaign.json')
    meta = read_json(meta_path)
    if meta is not None and meta.get('digest') != digest:
        raise CampaignError('%s holds another campaign (%s, a different spec or nominal config); '
                            'choose another --out or remove it' % (out, meta.get('name')))
    if os.path.exists(out) and meta is None and os.listdir(out):
        raise CampaignError('%s exists and is not a campaign directory' % out)
    os.makedirs(os.path.join(out, 'runs'), exist_ok=True)
    if meta is None:
        shutil.copyfile(spec.path, os.path.join(out, 'spec.yaml'))
        shutil.copyfile(spec.config, os.path.join(out, 'nominal.cfg'))
    if meta is None or meta.get('runs') != spec.runs:
        # A run does not depend on the number of runs: growing or cutting a campaign keeps
        # every run already flown.
        write_atomically(meta_path, json.dumps(
            {'name': spec.name, 'digest': digest, 'runs': spec.runs, 'seed': spec.seed},
            indent=1) + '\n')


def load_campaign(out):
    """The spec of an existing campaign directory (its own copy, with its number of runs)."""
    meta = read_json(os.path.join(out, 'campaign.json'))
    if meta is None:
        raise CampaignError('%s is not a campaign directory (no campaign.json)' % out)
    spec = specmod.load(os.path.join(out, 'spec.yaml'), config=os.path.join(out, 'nominal.cfg'))
    spec.runs = meta.get('runs', spec.runs)
    return spec


def deterministic(summary):
    """A run summary without its measured times (what must be identical between flights)."""
    return {k: v for k, v in summary.items() if k not in TIMING_KEYS}


def status_of(out, index):
    return read_json(os.path.join(run_dir(out, index), 'status.json'))


def pending(out, runs):
    """Indices of the runs not done."""
    return [i for i in range(runs) if not (status_of(out, i) or {}).get('completed')]


def _dying_with_parent(cmd):
    """cmd, SIGKILLed when the thread that started it ends (PR_SET_PDEATHSIG through util-linux's
    setpriv; preexec_fn is unsafe with threads): a killed campaign leaves no run flying behind it
    into a directory a resumed campaign is about to use."""
    return ['setpriv', '--pdeathsig', 'KILL', '--'] + cmd if shutil.which('setpriv') else cmd


def fly(out, index, sil, spec, timeout_s, dest=None, keep_log=False):
    """Flies run `index` in its run directory (or in `dest`); returns its status (also written to
    status.json when the disk lets it). Never raises for the run's own failures: they are its
    status."""
    d = dest or run_dir(out, index)
    status = {'index': index, 'completed': False, 'exit_code': None, 'signal': None,
              'result': None, 'error': None}
    start = time.monotonic()
    try:
        os.makedirs(d, exist_ok=True)
        for stale in ('status.json', 'summary.json', LOG_NAME):
            if os.path.exists(os.path.join(d, stale)):
                os.remove(os.path.join(d, stale))
        overrides = specmod.overrides(spec, index)
        summary_path = os.path.join(d, 'summary.json')
        log_path = os.path.join(d, LOG_NAME)
        cmd = sil_command(sil, out, index, overrides, summary_path, log_path)
        write_atomically(os.path.join(d, 'run.json'), json.dumps(
            {'index': index, 'seed': specmod.run_seed(spec.seed, index),
             'overrides': overrides, 'command': cmd}, indent=1) + '\n')
        with open(os.path.join(d, 'stderr.txt'), 'w', encoding='utf-8') as err:
            try:
                proc = subprocess.run(_dying_with_parent(cmd), stdout=subprocess.DEVNULL,
                                      stderr=err, timeout=timeout_s, check=False)
                code = proc.returncode
            except subprocess.TimeoutExpired:
                code = None
                status['error'] = 'timed out after %g s (killed)' % timeout_s
        if code is not None and code < 0:
            status['signal'] = -code
            status['error'] = 'killed by signal %d (%s)' % (-code, signal.Signals(-code).name)
        status['exit_code'] = code
        summary = read_json(summary_path)
        if summary is not None:
            status['result'] = summary.get('result')
        if code is not None and code >= 0:
            if summary is None:
                status['error'] = 'exit %d without a summary (see stderr.txt)' % code
            elif VERDICT_EXIT.get(status['result']) != code:
                status['error'] = 'exit %d with result %r in the summary' % (code,
                                                                            status['result'])
            elif summary.get('records_lost', 0):
                # Its verdict is about the disk, not the navigation.
                status['error'] = 'the LCM log lost %d records (a full disk?)' % (
                    summary['records_lost'])
            else:
                status['completed'] = True
        # The LCM log stays for runs that failed or did not complete; reproduce re-flies others.
        if (not keep_log and status['completed'] and status['result'] != 'failed' and
                os.path.exists(log_path)):
            os.remove(log_path)
        status['wall_s'] = round(time.monotonic() - start, 3)
        status['host'] = socket.gethostname()
        write_atomically(os.path.join(d, 'status.json'), json.dumps(status, indent=1) + '\n')
    except OSError as e:
        status['completed'] = False
        status['error'] = 'run %d: %s: %s' % (index, e.filename or d, e.strerror)
    return status


def reproduce(out, index, sil, spec):
    """Flies run `index` again into its reproduce/ directory, keeping the LCM log, unless that was
    done before. Returns (status, identical): whether the summary equals the campaign's apart from
    the measured times (None when either summary is missing)."""
    dest = os.path.join(run_dir(out, index), 'reproduce')
    status = read_json(os.path.join(dest, 'status.json'))
    if not (status or {}).get('completed'):
        status = fly(out, index, sil, spec, spec.timeout_s, dest=dest, keep_log=True)
    original = read_json(os.path.join(run_dir(out, index), 'summary.json'))
    again = read_json(os.path.join(dest, 'summary.json'))
    if original is None or again is None:
        return status, None
    return status, deterministic(original) == deterministic(again)


def describe(status):
    if status['completed']:
        return status['result']
    return status['error'] or 'not completed'


def run_local(spec, out, sil, jobs, progress=True):
    """Flies the pending runs with `jobs` worker threads (each one swf-sil process at a time).
    Returns the statuses of the runs flown now."""
    todo = pending(out, spec.runs)
    print('campaign %s: %d runs, %d done, %d to fly with %d local workers' % (
        spec.name, spec.runs, spec.runs - len(todo), len(todo), jobs), flush=True)
    statuses = []
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        futures = [pool.submit(fly, out, i, sil, spec, spec.timeout_s) for i in todo]
        try:
            for n, fut in enumerate(futures, 1):
                s = fut.result()
                statuses.append(s)
                if progress:
                    print('  run %5d: %s (%d/%d)' % (s['index'], describe(s), n, len(todo)),
                          flush=True)
        except KeyboardInterrupt:
            for fut in futures:
                fut.cancel()
            raise
    return statuses


def run_slurm(spec, out, sil, partition=None, time_limit_min=None, max_parallel=None,
              wait=True, poll_s=2.0, chunk=1000):
    """Submits the pending runs as Slurm array jobs (at most `chunk` tasks each; every task flies
    one run through `swf_campaign.py worker`), and with wait=True waits until they left the
    queue. OUT must be on a filesystem the compute nodes share."""
    for tool in ('sbatch', 'squeue'):
        if shutil.which(tool) is None:
            raise CampaignError('%s not found: the slurm engine needs the Slurm client '
                                '(Debian: slurm-client) and a reachable cluster' % tool)
    todo = pending(out, spec.runs)
    print('campaign %s: %d runs, %d done, %d to submit to Slurm' % (
        spec.name, spec.runs, spec.runs - len(todo), len(todo)), flush=True)
    if not todo:
        return []
    slurm_dir = os.path.join(out, 'slurm')
    os.makedirs(slurm_dir, exist_ok=True)
    script = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', 'swf_campaign.py'))
    minutes = time_limit_min or max(1, int(spec.timeout_s / 60.0 + 1.5))
    jobs = []
    for start in range(0, len(todo), chunk):
        part = todo[start:start + chunk]
        list_path = os.path.join(slurm_dir, 'chunk_%05d.txt' % (start // chunk))
        write_atomically(list_path, ''.join('%d\n' % i for i in part))
        wrap = '%s %s worker %s --list %s --sil %s' % (
            shlex.quote(sys.executable), shlex.quote(script), shlex.quote(os.path.abspath(out)),
            shlex.quote(os.path.abspath(list_path)), shlex.quote(os.path.abspath(sil)))
        array = '0-%d' % (len(part) - 1) + ('%%%d' % max_parallel if max_parallel else '')
        cmd = ['sbatch', '--parsable', '--job-name', 'swf-' + spec.name, '--array', array,
               '--cpus-per-task', '1', '--time', str(minutes),
               '--output', os.path.join(os.path.abspath(slurm_dir), '%A_%a.out'), '--wrap', wrap]
        if partition:
            cmd[1:1] = ['--partition', partition]
        proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                              check=False)
        if proc.returncode != 0:
            raise CampaignError('sbatch refused the array (exit %d): %s' % (
                proc.returncode, proc.stderr.strip()))
        job = proc.stdout.strip().split(';')[0]
        jobs.append(job)
        print('  submitted array job %s: %d runs' % (job, len(part)), flush=True)
    if not wait:
        print('  not waiting: `swf_campaign.py report %s` once the jobs are done' % out)
        return []
    failing_since = None
    while True:
        proc = subprocess.run(['squeue', '-h', '-j', ','.join(jobs), '-o', '%i %T'],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                              check=False)
        # A finished job leaves squeue after MinJobAge; then squeue calls its id invalid.
        if (proc.returncode == 0 and not proc.stdout.strip()) or 'Invalid job id' in proc.stderr:
            break
        if proc.returncode != 0:
            failing_since = failing_since or time.monotonic()
            if time.monotonic() - failing_since > 60.0:
                raise CampaignError('squeue keeps failing (%s); the jobs %s may still run: '
                                    '`swf_campaign.py report %s` once they are done' % (
                                        proc.stderr.strip(), ','.join(jobs), out))
        else:
            failing_since = None
        time.sleep(poll_s)
    statuses = []
    for i in todo:
        s = status_of(out, i)
        if s is None:
            s = {'index': i, 'completed': False, 'error': 'no status: the task ended before the run '
                 'did (killed, out of time or a full disk? see %s)' % os.path.join(
                     slurm_dir, '%s_*.out' % jobs[0])}
        statuses.append(s)
    return statuses


def worker(out, sil, indices):
    """A Slurm task: flies the runs given (normally one). Exit 0 when each completed."""
    spec = load_campaign(out)
    failed = 0
    for i in indices:
        s = fly(out, i, sil, spec, spec.timeout_s)
        print('run %d: %s' % (i, describe(s)), flush=True)
        failed += not s['completed']
    return 1 if failed else 0


def command_line(argv):
    return ' '.join(shlex.quote(a) for a in argv)
