#!/usr/bin/python3
"""Monte Carlo dispersion campaigns of the simulated descent, flown by swf-sil in lockstep.

  swf_campaign.py run SPEC [--out DIR] [--engine local|slurm] [--jobs N] [--sil PATH]
      validate the spec, fly every run not yet done (resumable), write the report
  swf_campaign.py report OUT          aggregate OUT's runs again into OUT/report/
  swf_campaign.py reproduce OUT RUN   fly one run again alone, keep its LCM log, compare
  swf_campaign.py show SPEC RUN       print the swf-sil command of one run
  swf_campaign.py worker OUT ...      one Slurm array task (used by the slurm engine)

Exit status: 0 every run completed (whatever its navigation verdict, which the report gives);
1 some runs did not complete (crashed, killed, timed out, a write failed: listed, their inputs
kept; rerun the same command to fly only those) or a reproduced run differs; 2 refused (a bad
spec, a missing swf-sil, OUT holding another campaign). tools/campaign/README.md has the spec
format and the cluster setup.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from swfcampaign import engine, report, spec as specmod  # noqa: E402

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
DEFAULT_SIL = os.path.join(ROOT, 'build', 'release', 'bin', 'swf-sil')


def refly_worst(out, spec, sil, rep):
    """The worst runs' LCM logs: fly each again with its log kept (lockstep runs are
    deterministic) and check that it gives the same summary."""
    reproduced = {}
    for w in rep['worst_runs'][:spec.keep_worst]:
        status, same = engine.reproduce(out, w['run'], sil, spec)
        reproduced[w['run']] = bool(same)
        print('  worst run %d re-flown with its log: %s' % (
            w['run'], 'summary identical' if same else 'SUMMARY DIFFERS: ' +
            engine.describe(status)), flush=True)
    return reproduced


def write_report(out, spec, sil, refly, plots):
    rep, _ = report.write(out, spec, with_plots=False)
    reproduced = refly_worst(out, spec, sil, rep) if refly and spec.keep_worst > 0 else {}
    # The worst runs' own plots come from swf-plot, built beside swf-sil.
    plot_tool = os.path.join(os.path.dirname(os.path.abspath(sil)), 'swf-plot')
    rep, plot_errors = report.write(out, spec, reproduced, with_plots=plots, plot_tool=plot_tool)
    n = rep['navigation']['final_position_error_m']
    print('campaign %s: %d/%d runs completed %s; final position error p50 %s m, p95 %s m, max '
          '%s m; report %s' % (
              spec.name, rep['completed'], rep['runs'], rep['results'], report.fmt(n['p50']),
              report.fmt(n['p95']), report.fmt(n['max']),
              os.path.join(out, 'report', 'report.md')), flush=True)
    for r in rep['not_completed']:
        print('  run %d did not complete: %s (inputs: %s)' % (r['run'], r['error'], r['inputs']),
              file=sys.stderr)
    bad_repro = [k for k, v in reproduced.items() if not v]
    if bad_repro:
        print('  re-flown runs differ from the campaign: %s' % bad_repro, file=sys.stderr)
    for e in plot_errors:
        print('  plots: %s' % e, file=sys.stderr)
    return 0 if not rep['not_completed'] and not bad_repro and not plot_errors else 1


def cmd_run(a):
    spec = specmod.load(a.spec)
    if a.runs is not None:
        spec.runs = a.runs
    engine.check_sil(a.sil)
    engine.check_against_sil(spec, a.sil)
    out = a.out or os.path.join(ROOT, 'out', 'campaign', spec.name)
    engine.prepare(spec, out)
    spec = engine.load_campaign(out)
    if a.engine == 'local':
        statuses = engine.run_local(spec, out, a.sil, a.jobs)
    else:
        statuses = engine.run_slurm(spec, out, a.sil, partition=a.partition,
                                    time_limit_min=a.time_limit, max_parallel=a.max_parallel,
                                    wait=not a.no_wait)
        if a.no_wait:
            return 0
    lost = [s for s in statuses if not s['completed']]
    if lost:
        print('campaign %s: %d of the %d runs flown now did not complete (rerun the same command '
              'to fly them again):' % (spec.name, len(lost), len(statuses)), file=sys.stderr)
        for s in lost:
            print('  run %d: %s' % (s['index'], engine.describe(s)), file=sys.stderr)
    try:
        code = write_report(out, spec, a.sil, refly=not a.no_refly, plots=True)
    except OSError as e:
        print('campaign %s: cannot write the report: %s: %s (the runs are kept; '
              '`swf_campaign.py report %s` retries)' % (spec.name, e.filename, e.strerror, out),
              file=sys.stderr)
        return 1
    return 1 if lost else code


def cmd_report(a):
    spec = engine.load_campaign(a.out)
    return write_report(a.out, spec, a.sil, refly=not a.no_refly, plots=not a.no_plots)


def cmd_reproduce(a):
    spec = engine.load_campaign(a.out)
    engine.check_sil(a.sil)
    if not 0 <= a.run < spec.runs:
        raise engine.CampaignError('run %d: the campaign has runs 0 .. %d' % (a.run,
                                                                            spec.runs - 1))
    dest = os.path.join(engine.run_dir(a.out, a.run), 'reproduce')
    if os.path.exists(os.path.join(dest, 'status.json')):
        os.remove(os.path.join(dest, 'status.json'))
    status, same = engine.reproduce(a.out, a.run, a.sil, spec)
    run = engine.read_json(os.path.join(dest, 'run.json')) or {}
    print('run %d: %s; flown again in %s (LCM log %s)' % (
        a.run, engine.describe(status), dest, engine.LOG_NAME))
    print('  command: %s' % engine.command_line(run.get('command', [])))
    if same is None:
        print('  no campaign summary to compare with' if status.get('completed')
              else '  the run did not complete', file=sys.stderr)
        return 1
    print('  summary %s the campaign\'s (apart from measured times)' % (
        'identical to' if same else 'DIFFERS from'))
    return 0 if same else 1


def cmd_show(a):
    spec = specmod.load(a.spec)
    if not 0 <= a.run < spec.runs:
        raise engine.CampaignError('run %d: the campaign has runs 0 .. %d' % (a.run,
                                                                            spec.runs - 1))
    out = os.path.join(ROOT, 'out', 'campaign', spec.name)
    d = engine.run_dir(out, a.run)
    cmd = engine.sil_command(a.sil, out, a.run, specmod.overrides(spec, a.run),
                             os.path.join(d, 'summary.json'), os.path.join(d, engine.LOG_NAME))
    cmd[2] = spec.config
    print(engine.command_line(cmd))
    return 0


def cmd_worker(a):
    indices = [a.index] if a.index is not None else []
    if a.list:
        task = os.environ.get('SLURM_ARRAY_TASK_ID')
        if task is None:
            raise engine.CampaignError('worker --list needs SLURM_ARRAY_TASK_ID')
        with open(a.list, encoding='utf-8') as f:
            lines = f.read().split()
        indices.append(int(lines[int(task)]))
    return engine.worker(a.out, a.sil, indices)


def parse(argv):
    p = argparse.ArgumentParser(prog='swf_campaign.py', description=__doc__.split('\n')[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=__doc__.split('\n', 1)[1])
    sub = p.add_subparsers(dest='command', required=True)
    r = sub.add_parser('run', help='fly a campaign (resumable) and write its report')
    r.add_argument('spec')
    r.add_argument('--out', help='campaign directory (default out/campaign/NAME)')
    r.add_argument('--engine', choices=('local', 'slurm'), default='local')
    r.add_argument('--runs', type=int, help='fly this many runs instead of the spec\'s (run i '
                   'is the same either way: a campaign grows in place)')
    r.add_argument('--jobs', type=int, default=os.cpu_count() or 1,
                   help='local engine: runs at once (default: the number of cores)')
    r.add_argument('--partition', help='slurm engine: the partition (default: the cluster\'s)')
    r.add_argument('--time-limit', type=int, help='slurm engine: minutes per task (default: '
                   'from the spec\'s timeout_s)')
    r.add_argument('--max-parallel', type=int, help='slurm engine: tasks running at once')
    r.add_argument('--no-wait', action='store_true',
                   help='slurm engine: submit and exit; `report OUT` later')
    r.add_argument('--no-refly', action='store_true',
                   help='do not fly the worst runs again to keep their LCM logs')
    rep = sub.add_parser('report', help='aggregate a campaign directory again')
    rep.add_argument('out')
    rep.add_argument('--no-plots', action='store_true')
    rep.add_argument('--no-refly', action='store_true')
    rp = sub.add_parser('reproduce', help='fly one run again, keep its log, compare')
    rp.add_argument('out')
    rp.add_argument('run', type=int)
    s = sub.add_parser('show', help='print one run\'s swf-sil command')
    s.add_argument('spec')
    s.add_argument('run', type=int)
    w = sub.add_parser('worker', help='one Slurm array task (internal)')
    w.add_argument('out')
    w.add_argument('--index', type=int)
    w.add_argument('--list')
    for q in (r, rep, rp, s, w):
        q.add_argument('--sil', default=DEFAULT_SIL,
                       help='the swf-sil binary (default build/release/bin/swf-sil)')
    a = p.parse_args(argv)
    if getattr(a, 'jobs', 1) < 1:
        p.error('--jobs must be at least 1')
    if getattr(a, 'runs', None) is not None and not 1 <= a.runs <= 100000:
        p.error('--runs must be in [1, 100000]')
    return a


def main(argv):
    a = parse(argv)
    # The simulator's terrain imagery, for runs started from any directory (Slurm tasks inherit
    # the environment).
    os.environ.setdefault('SWF_SHARED_DIR', os.path.join(os.path.dirname(ROOT), 'shared'))
    handlers = {'run': cmd_run, 'report': cmd_report, 'reproduce': cmd_reproduce,
                'show': cmd_show, 'worker': cmd_worker}
    try:
        return handlers[a.command](a)
    except specmod.SpecError as e:
        print('swf_campaign: %s' % e, file=sys.stderr)
        return 2
    except engine.CampaignError as e:
        print('swf_campaign: %s' % e, file=sys.stderr)
        return 2
    except OSError as e:
        print('swf_campaign: %s: %s' % (e.filename or '', e.strerror), file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print('swf_campaign: interrupted; done runs are kept, rerun to resume', file=sys.stderr)
        return 1


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
