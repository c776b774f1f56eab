"""Aggregating a campaign's runs into report.json, report.md and PNG plots (OUT/report/): the
campaign's own plots (matplotlib) and each re-flown worst run's plots, drawn by swf-plot from its
LCM log (tools/plot: the pictures swf-sil draws for the demo).

Everything in report.json except "timing" is a function of the runs' estimates, so two engines
that flew the same campaign give the same report apart from the measured times.
"""
import json
import math
import os
import subprocess

from . import engine
from . import spec as specmod

# Position NEES of a consistent estimator is chi-square with 3 degrees of freedom: 95 % of the
# outputs fall in its central interval.
CHI2_3_CENTRAL_95 = (0.2158, 9.3484)
DIVERGED_FLAG_BIT = 2  # nav_state_t.INTEGRITY_DIVERGED = 4
HEIGHT_CLASSES = ['[1, 2) x threshold', '[2, 4) x threshold', '>= 4 x threshold']


def percentile(values, q):
    """Linear interpolation between closest ranks (q in [0, 100]); None for no values."""
    v = sorted(x for x in values if x is not None and math.isfinite(x))
    if not v:
        return None
    pos = (len(v) - 1) * q / 100.0
    lo = int(math.floor(pos))
    hi = min(lo + 1, len(v) - 1)
    return v[lo] + (v[hi] - v[lo]) * (pos - lo)


def stats(values):
    v = [x for x in values if x is not None and math.isfinite(x)]
    if not v:
        return {'n': 0, 'p50': None, 'p95': None, 'p99': None, 'max': None, 'mean': None}
    return {'n': len(v), 'p50': percentile(v, 50), 'p95': percentile(v, 95),
            'p99': percentile(v, 99), 'max': max(v), 'mean': sum(v) / len(v)}


def clean(x):
    """JSON without inf/nan: non-finite numbers become null, floats rounded to 6 digits."""
    if isinstance(x, float):
        return float('%.6g' % x) if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: clean(v) for k, v in x.items()}
    if isinstance(x, list):
        return [clean(v) for v in x]
    return x


def altitude_bins(max_altitude):
    """Bin edges of about 10 bins of a round width up to the highest altitude."""
    top = max(1.0, max_altitude)
    width = 1.0
    for w in (1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0):
        width = w
        if top / w <= 12:
            break
    n = int(math.ceil(top / width))
    return [i * width for i in range(n + 1)]


def bin_of(edges, a):
    if a is None or not math.isfinite(a):
        return None
    for i in range(len(edges) - 1):
        if a < edges[i + 1]:
            return i
    return len(edges) - 2


def load_runs(out, runs):
    loaded = []
    for i in range(runs):
        d = engine.run_dir(out, i)
        status = engine.status_of(out, i) or {'index': i, 'completed': False,
                                              'error': 'never flown (or its status was lost)'}
        run = engine.read_json(os.path.join(d, 'run.json')) or {}
        summary = engine.read_json(os.path.join(d, 'summary.json')) if status.get(
            'completed') else None
        loaded.append({'index': i, 'status': status, 'run': run, 'summary': summary})
    return loaded


def reproduce_command(out, index):
    return 'tools/campaign/swf_campaign.py reproduce %s %d' % (out, index)


def aggregate(out, spec):
    runs = load_runs(out, spec.runs)
    done = [r for r in runs if r['summary'] is not None]
    report = {'campaign': spec.name, 'seed': spec.seed, 'runs': spec.runs,
              'completed': len(done), 'not_completed': []}
    for r in runs:
        if r['summary'] is None:
            s = r['status']
            report['not_completed'].append({
                'run': r['index'], 'exit_code': s.get('exit_code'), 'signal': s.get('signal'),
                'error': s.get('error'), 'inputs': os.path.join(engine.run_dir(out, r['index'])),
                'reproduce': reproduce_command(out, r['index'])})
    results = {}
    for r in done:
        res = r['summary'].get('result')
        results[res] = results.get(res, 0) + 1
    report['results'] = results

    # Navigation error by altitude and at the end of the descent.
    outputs = []  # (altitude, position error, attitude error, nees, status, hpl, vpl, h, v)
    for r in done:
        o = r['summary'].get('outputs') or {}
        nees = r['summary'].get('position_nees') or []
        for k in range(len(o.get('frame', []))):
            h, v = o['horizontal_error_m'][k], o['vertical_error_m'][k]
            e = math.hypot(h, v) if h is not None and v is not None else None
            outputs.append((o['altitude_m'][k], e, o['attitude_error_deg'][k],
                            nees[k] if k < len(nees) else None, o['status'][k], o['hpl_m'][k],
                            o['vpl_m'][k], h, v))
    edges = altitude_bins(max([x[0] for x in outputs if x[0] is not None] or [1.0]))
    by_alt = []
    for b in range(len(edges) - 1):
        sel = [x for x in outputs if bin_of(edges, x[0]) == b]
        by_alt.append({'altitude_m': [edges[b], edges[b + 1]],
                       'position_error_m': stats([x[1] for x in sel]),
                       'attitude_error_deg': stats([x[2] for x in sel]),
                       'mean_position_nees': stats([x[3] for x in sel])['mean']})
    final = [(r['summary'].get('final_pose_error_m'), r) for r in done]
    report['navigation'] = {
        'final_position_error_m': stats([f for f, _ in final]),
        'final_attitude_error_deg': stats([r['summary'].get('final_attitude_error_deg')
                                           for r in done]),
        'pose_rms_error_m': stats([r['summary'].get('pose_rms_error_m') for r in done]),
        'by_altitude': by_alt}

    # Consistency: NEES and the protection levels.
    nees = [x[3] for x in outputs if x[3] is not None and math.isfinite(x[3])]
    inside = sum(1 for n in nees if CHI2_3_CENTRAL_95[0] <= n <= CHI2_3_CENTRAL_95[1])
    valid_with_pl = [x for x in outputs if x[4] == 0 and (x[5] or 0) > 0 and (x[6] or 0) > 0]
    held = sum(1 for x in valid_with_pl if x[7] <= x[5] and x[8] <= x[6])
    report['consistency'] = {
        'outputs_with_covariance': len(nees),
        'mean_position_nees': sum(nees) / len(nees) if nees else None,
        'nees_inside_chi2_95': inside / len(nees) if nees else None,
        'valid_outputs_with_protection': len(valid_with_pl),
        'protection_held_outputs': held,
        'protection_held': held / len(valid_with_pl) if valid_with_pl else None,
        'runs_with_protection_violations': sum(
            1 for r in done if r['summary'].get('integrity', {}).get('protection_violations', 0))}

    # Integrity: divergence and INVALID.
    def integrity(r, key):
        return r['summary'].get('integrity', {}).get(key, 0) or 0

    def flag(r, bit):
        counts = r['summary'].get('integrity', {}).get('flag_counts') or []
        return counts[bit] if bit < len(counts) else 0
    report['integrity'] = {
        'runs_with_invalid_frames': sum(1 for r in done if integrity(r, 'frames_invalid') > 0),
        'invalid_frames': sum(integrity(r, 'frames_invalid') for r in done),
        'runs_with_divergence_detected': sum(1 for r in done if flag(r, DIVERGED_FLAG_BIT) > 0),
        'runs_with_restarts': sum(1 for r in done if integrity(r, 'restarts') > 0),
        'degraded_frames': sum(integrity(r, 'frames_degraded') for r in done)}

    report['sensitivity'] = sensitivity(spec, done)
    report['hazard'] = hazard_by_altitude(done)
    report['timing'] = timing(done)
    worst = sorted((r for r in done if r['summary'].get('final_pose_error_m') is not None),
                   key=lambda r: (-r['summary']['final_pose_error_m'], r['index']))
    report['worst_runs'] = [{
        'run': r['index'], 'result': r['summary'].get('result'),
        'final_position_error_m': r['summary'].get('final_pose_error_m'),
        'pose_rms_error_m': r['summary'].get('pose_rms_error_m'),
        'reasons': r['summary'].get('result_reasons'),
        'overrides': r['run'].get('overrides', {}),
        'reproduce': reproduce_command(out, r['index'])} for r in worst[:max(1, spec.keep_worst)]]
    report['failed_runs'] = [{'run': r['index'], 'reasons': r['summary'].get('result_reasons'),
                              'reproduce': reproduce_command(out, r['index'])}
                             for r in done if r['summary'].get('result') == 'failed']
    return clean(report), outputs, edges, done


def hazard_by_altitude(done):
    maps = [m for r in done for m in (r['summary'].get('hazard_by_map') or [])]
    edges = altitude_bins(max([m['altitude_m'] for m in maps if m.get('altitude_m') is not None]
                              or [1.0]))
    rows = []
    for b in range(len(edges) - 1):
        sel = [m for m in maps if bin_of(edges, m.get('altitude_m')) == b]
        resolved = [sum(m['rocks_resolved_by_height'][c] for m in sel) for c in range(3)]
        detected = [sum(m['rocks_detected_by_height'][c] for m in sel) for c in range(3)]
        free = sum(m['rock_free_cells'] for m in sel)
        false = sum(m['false_rock_cells'] for m in sel)
        rows.append({'altitude_m': [edges[b], edges[b + 1]], 'maps': len(sel),
                     'rocks_resolved_by_height': resolved, 'rocks_detected_by_height': detected,
                     'detection_probability_by_height': [d / n if n else None
                                                         for d, n in zip(detected, resolved)],
                     'false_alarm_rate': false / free if free else None})
    resolved = [sum(m['rocks_resolved_by_height'][c] for m in maps) for c in range(3)]
    detected = [sum(m['rocks_detected_by_height'][c] for m in maps) for c in range(3)]
    free = sum(m['rock_free_cells'] for m in maps)
    false = sum(m['false_rock_cells'] for m in maps)
    overall = {'rocks_resolved_by_height': resolved, 'rocks_detected_by_height': detected,
               'detection_probability_by_height': [d / n if n else None
                                                   for d, n in zip(detected, resolved)],
               'detection_probability': sum(detected) / sum(resolved) if sum(resolved) else None,
               'rock_free_cells': free, 'false_rock_cells': false,
               'false_alarm_rate': false / free if free else None}
    sites = [r['summary'].get('safe_site') for r in done]
    with_site = [s for s in sites if s is not None]
    clear = sum(1 for s in with_site if not s.get('on_truth_hazard'))
    return {'maps': len(maps), 'height_classes': HEIGHT_CLASSES, 'by_altitude': rows,
            'all_maps': overall,
            'runs_with_safe_site': len(with_site),
            'safe_site_clear_of_truth_hazards': clear,
            'safe_site_success_rate': clear / len(done) if done else None}


def ranks(values):
    """Ranks 1..n, ties sharing their mean rank."""
    order = sorted(range(len(values)), key=lambda k: values[k])
    r = [0.0] * len(values)
    k = 0
    while k < len(order):
        m = k
        while m + 1 < len(order) and values[order[m + 1]] == values[order[k]]:
            m += 1
        for j in range(k, m + 1):
            r[order[j]] = (k + m) / 2.0 + 1.0
        k = m + 1
    return r


def spearman(x, y):
    if len(x) < 3:
        return None
    rx, ry = ranks(x), ranks(y)
    mx, my = sum(rx) / len(rx), sum(ry) / len(ry)
    sxy = sum((a - mx) * (b - my) for a, b in zip(rx, ry))
    sxx = sum((a - mx) ** 2 for a in rx)
    syy = sum((b - my) ** 2 for b in ry)
    return sxy / math.sqrt(sxx * syy) if sxx > 0 and syy > 0 else None


def sensitivity(spec, done):
    """Which dispersion goes with a larger pose RMS error: Spearman's rank correlation of each
    numeric dispersion's distance from its nominal (the mean of a normal, the value of a uniform;
    vectors by their norm) with the run's pose RMS error, and for a choice the median error per
    value. A screening aid, not a cause: with N runs |rho| below about 2 / sqrt(N) is noise."""
    runs = [r for r in done if r['summary'].get('pose_rms_error_m') is not None]
    err = [r['summary']['pose_rms_error_m'] for r in runs]
    numeric, choices = [], []
    for key, d in sorted(spec.dispersions.items()):
        values = [r['run'].get('overrides', {}).get(key) for r in runs]
        if d.kind == specmod.RUN_SEED or any(v is None for v in values):
            continue
        if d.kind == 'choice':
            groups = {}
            for v, e in zip(values, err):
                groups.setdefault(v, []).append(e)
            choices.append({'key': key, 'values': {v: {'runs': len(g), 'pose_rms_p50_m':
                                                       percentile(g, 50)}
                                                   for v, g in sorted(groups.items())}})
            continue
        nominal = d.params[0] if d.kind == 'normal' else [0.0] * len(d.params[0])
        x = [math.sqrt(sum((float(c) - m) ** 2 for c, m in zip(v.split(','), nominal)))
             for v in values]
        numeric.append({'key': key, 'measure': 'abs(value - mean)' if d.kind == 'normal'
                        else ('norm(value)' if len(nominal) > 1 else 'value'),
                        'spearman_rho': spearman(x, err)})
    numeric.sort(key=lambda row: -abs(row['spearman_rho'] or 0.0))
    return {'runs': len(runs), 'numeric': numeric, 'choices': choices,
            'noise_level': 2.0 / math.sqrt(len(runs)) if runs else None}


def timing(done):
    stages = {}
    for r in done:
        for name, s in (r['summary'].get('stages') or {}).items():
            stages.setdefault(name, {'p99_ms': [], 'max_ms': []})
            stages[name]['p99_ms'].append(s.get('p99_ms'))
            stages[name]['max_ms'].append(s.get('max_ms'))
    return {'stages': {name: {'p99_ms_median_over_runs': percentile(v['p99_ms'], 50),
                              'p99_ms_worst_run': max([x for x in v['p99_ms'] if x is not None]
                                                      or [0.0]),
                              'max_ms': max([x for x in v['max_ms'] if x is not None] or [0.0])}
                       for name, v in stages.items()},
            'overruns': sum(r['summary'].get('overruns', 0) or 0 for r in done),
            'runs_with_overruns': sum(1 for r in done if r['summary'].get('overruns')),
            'hazard_overruns': sum(r['summary'].get('hazard_overruns', 0) or 0 for r in done),
            'runs_with_hazard_overruns': sum(1 for r in done
                                             if r['summary'].get('hazard_overruns')),
            'lockstep_wait_cycles': sum((r['summary'].get('lockstep_waits') or {}).get('cycles', 0)
                                        for r in done),
            'lockstep_wait_max_ms': max([(r['summary'].get('lockstep_waits') or {})
                                         .get('max_ms', 0.0) for r in done] or [0.0]),
            'allocations_after_start': sum(max(0, r['summary'].get('allocations_after_start', 0)
                                               or 0) for r in done),
            'wall_s_per_run': stats([r['status'].get('wall_s') for r in done])}


def plots(report, outputs, edges, done, report_dir):
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    written = []
    name = report['campaign']

    def save(fig, file):
        fig.tight_layout()
        fig.savefig(os.path.join(report_dir, file), dpi=110)
        plt.close(fig)
        written.append(file)

    finals = sorted(r['summary']['final_pose_error_m'] for r in done
                    if r['summary'].get('final_pose_error_m') is not None)
    if finals:
        fig, ax = plt.subplots(figsize=(6.4, 4.2))
        ax.step(finals, [(k + 1) / len(finals) for k in range(len(finals))], where='post',
                label='%d runs' % len(finals))
        ax.set_xscale('log' if finals[0] > 0 else 'linear')
        ax.set_xlabel('final position error (m)')
        ax.set_ylabel('fraction of runs')
        ax.set_title('%s: final position error, CDF' % name)
        ax.grid(True, alpha=0.3)
        ax.legend()
        save(fig, 'final_error_cdf.png')

    rows = [b for b in report['navigation']['by_altitude'] if b['position_error_m']['n']]
    if rows:
        mid = [0.5 * (b['altitude_m'][0] + b['altitude_m'][1]) for b in rows]
        for key, file, label in (('position_error_m', 'error_by_altitude.png',
                                  'position error (m)'),
                                 ('attitude_error_deg', 'attitude_by_altitude.png',
                                  'attitude error (deg)')):
            fig, ax = plt.subplots(figsize=(6.4, 4.2))
            for q, style in (('p50', 'o-'), ('p95', 's-'), ('p99', '^-'), ('max', 'x--')):
                ax.plot(mid, positive([b[key][q] for b in rows]), style, label=q)
            ax.set_xlabel('true altitude above the terrain (m)')
            ax.set_ylabel(label)
            ax.set_yscale('log')
            ax.invert_xaxis()
            ax.set_title('%s: %s by altitude' % (name, label.split(' (')[0]))
            ax.grid(True, alpha=0.3)
            ax.legend(title='over runs and outputs')
            save(fig, file)
        fig, ax = plt.subplots(figsize=(6.4, 4.2))
        ax.plot(mid, positive([b['mean_position_nees'] for b in rows]), 'o-',
                label='mean position NEES')
        ax.axhline(3.0, color='k', lw=1, label='consistent: 3')
        ax.axhspan(*CHI2_3_CENTRAL_95, color='g', alpha=0.1,
                   label='chi-square(3) central 95 % of one output')
        ax.set_xlabel('true altitude above the terrain (m)')
        ax.set_ylabel('position NEES (dimensionless)')
        ax.set_yscale('log')
        ax.invert_xaxis()
        ax.set_title('%s: position NEES by altitude' % name)
        ax.grid(True, alpha=0.3)
        ax.legend()
        save(fig, 'nees_by_altitude.png')

    hz = [b for b in report['hazard']['by_altitude'] if b['maps']]
    if hz:
        mid = [0.5 * (b['altitude_m'][0] + b['altitude_m'][1]) for b in hz]
        fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(6.4, 6.4), sharex=True)
        for c, label in enumerate(HEIGHT_CLASSES):
            pts = [(m, b['detection_probability_by_height'][c]) for m, b in zip(mid, hz)
                   if b['detection_probability_by_height'][c] is not None]
            if pts:
                ax1.plot([p[0] for p in pts], [p[1] for p in pts], 'o-',
                         label='rock height %s' % label)
        ax1.set_ylabel('detection probability')
        ax1.set_ylim(-0.05, 1.05)
        ax1.set_title('%s: hazard detection by altitude' % name)
        ax1.grid(True, alpha=0.3)
        if ax1.get_legend_handles_labels()[0]:
            ax1.legend(fontsize=8)
        pts = [(m, b['false_alarm_rate']) for m, b in zip(mid, hz)
               if b['false_alarm_rate'] is not None]
        ax2.plot([p[0] for p in pts], [p[1] for p in pts], 'o-', color='C3',
                 label='rock cells where the truth has none')
        ax2.set_xlabel('true altitude above the terrain (m)')
        ax2.set_ylabel('false-alarm rate (fraction of cells)')
        ax2.invert_xaxis()
        ax2.grid(True, alpha=0.3)
        ax2.legend(fontsize=8)
        save(fig, 'hazard_by_altitude.png')

    overall = report['hazard']['all_maps']
    if any(overall['rocks_resolved_by_height']):
        fig, ax = plt.subplots(figsize=(6.4, 3.8))
        xs = [c for c in range(len(HEIGHT_CLASSES))
              if overall['detection_probability_by_height'][c] is not None]
        ax.bar(xs, [overall['detection_probability_by_height'][c] for c in xs], color='C0',
               label='detected / resolved, every map')
        for c in xs:
            ax.annotate('%d / %d' % (overall['rocks_detected_by_height'][c],
                                     overall['rocks_resolved_by_height'][c]),
                        (c, overall['detection_probability_by_height'][c]), ha='center',
                        va='bottom', fontsize=8)
        ax.set_xticks(range(len(HEIGHT_CLASSES)))
        ax.set_xticklabels(['rock height ' + h for h in HEIGHT_CLASSES], fontsize=8)
        ax.set_ylabel('detection probability')
        ax.set_ylim(0, 1.1)
        ax.set_title('%s: hazard detection by rock height' % name)
        ax.grid(True, axis='y', alpha=0.3)
        ax.legend(fontsize=8, loc='lower right')
        save(fig, 'hazard_by_rock_height.png')

    stages = {}
    for r in done:
        for st, s in (r['summary'].get('stages') or {}).items():
            if s.get('p99_ms') is not None and s['p99_ms'] > 0:
                stages.setdefault(st, []).append(s['p99_ms'])
    if stages:
        fig, ax = plt.subplots(figsize=(7.2, 4.2))
        names = sorted(stages)
        box = ax.boxplot([stages[n] for n in names], labels=names)
        ax.legend([box['boxes'][0], box['medians'][0], box['whiskers'][0]],
                  ['quartiles of the runs', 'median run', 'range (1.5 IQR)'], fontsize=8)
        ax.set_yscale('log')
        ax.set_ylabel('per-run p99 (ms)')
        ax.set_xlabel('stage')
        ax.set_title('%s: stage time p99 over %d runs' % (name, len(done)))
        ax.grid(True, alpha=0.3)
        save(fig, 'stage_times.png')
    return written


def run_plots(out, report, reproduced, report_dir, plot_tool):
    """The worst runs' own plots (trajectory, attitude and landmark error, landmark map, hazard
    map): swf-plot on the LCM log each re-flight kept, into report/run_NNNNN/. Returns
    ({run: [PNG paths relative to report_dir]}, [errors])."""
    drawn, errors = {}, []
    for w in report['worst_runs']:
        if w['run'] not in reproduced:
            continue
        log = os.path.join(engine.run_dir(out, w['run']), 'reproduce', engine.LOG_NAME)
        dest = os.path.join(report_dir, 'run_%05d' % w['run'])
        os.makedirs(dest, exist_ok=True)
        try:
            p = subprocess.run([plot_tool, log, '--out', dest], capture_output=True, text=True,
                               check=False)
        except OSError as e:
            errors.append('run %d: cannot run %s: %s' % (w['run'], plot_tool, e.strerror))
            continue
        if p.returncode != 0:
            errors.append('run %d: swf-plot exited %d: %s' % (w['run'], p.returncode,
                                                               p.stderr.strip()))
        drawn[w['run']] = [os.path.relpath(line, report_dir) for line in p.stdout.split()]
    return drawn, errors


def fmt(v, digits=3):
    if v is None:
        return 'n/a'
    if isinstance(v, float):
        return '%.*g' % (digits, v)
    return str(v)


def percent(fraction):
    return 'n/a' if fraction is None else '%.1f %%' % (100.0 * fraction)


def positive(values):
    """Values for a log axis: zeros and unknowns become gaps."""
    return [v if v is not None and v > 0 else float('nan') for v in values]


def markdown(report, pngs, reproduced, worst_plots=None):
    n = report['navigation']
    c = report['consistency']
    i = report['integrity']
    h = report['hazard']
    t = report['timing']
    lines = ['# Campaign %s' % report['campaign'], '',
             '%d runs (campaign seed %d): %d completed (%s), %d not completed.' % (
                 report['runs'], report['seed'], report['completed'],
                 ', '.join('%d %s' % (v, k) for k, v in sorted(report['results'].items())) or
                 'none', len(report['not_completed'])), '']
    if report['not_completed']:
        lines += ['## Runs that did not complete', '',
                  '| run | exit | signal | error | inputs kept in |', '|---|---|---|---|---|']
        for r in report['not_completed']:
            lines.append('| %d | %s | %s | %s | `%s` |' % (r['run'], fmt(r['exit_code']),
                                                          fmt(r['signal']), r['error'],
                                                          r['inputs']))
        lines += ['', 'Rerun the same `run` command to fly them again (done runs are kept).', '']
    f = n['final_position_error_m']
    lines += ['## Navigation', '',
              'Final position error over %d runs: p50 %s m, p95 %s m, p99 %s m, max %s m. '
              'Final attitude error: p50 %s deg, max %s deg.' % (
                  f['n'], fmt(f['p50']), fmt(f['p95']), fmt(f['p99']), fmt(f['max']),
                  fmt(n['final_attitude_error_deg']['p50']),
                  fmt(n['final_attitude_error_deg']['max'])), '',
              '| altitude (m) | outputs | position error p50 / p95 / p99 / max (m) | '
              'attitude error p50 / max (deg) | mean NEES |', '|---|---|---|---|---|']
    for b in n['by_altitude']:
        p, a = b['position_error_m'], b['attitude_error_deg']
        if p['n']:
            lines.append('| %g-%g | %d | %s / %s / %s / %s | %s / %s | %s |' % (
                b['altitude_m'][0], b['altitude_m'][1], p['n'], fmt(p['p50']), fmt(p['p95']),
                fmt(p['p99']), fmt(p['max']), fmt(a['p50']), fmt(a['max']),
                fmt(b['mean_position_nees'])))
    lines += ['', '## Consistency and integrity', '',
              '- Position NEES: mean %s over %d outputs (3 when consistent); %s of them inside '
              'the chi-square(3) central 95 %% interval.' % (
                  fmt(c['mean_position_nees']), c['outputs_with_covariance'],
                  percent(c['nees_inside_chi2_95'])),
              '- Protection levels: the true error was inside them for %d of the %d VALID '
              'outputs that had them (%s); %d runs had a VALID output beyond its protection '
              'level.' % (c['protection_held_outputs'], c['valid_outputs_with_protection'],
                          percent(c['protection_held']), c['runs_with_protection_violations']),
              '- INVALID: %d frames in %d runs. Divergence detected in %d runs, filter restarts '
              'in %d.' % (i['invalid_frames'], i['runs_with_invalid_frames'],
                          i['runs_with_divergence_detected'], i['runs_with_restarts']), '',
              '## Hazard detection', '',
              '%d hazard maps. Safe site: %d runs chose one, %d clear of every true hazard '
              '(success rate %s of the completed runs).' % (
                  h['maps'], h['runs_with_safe_site'], h['safe_site_clear_of_truth_hazards'],
                  percent(h['safe_site_success_rate'])), '',
              '| altitude (m) | maps | P_d by rock height (%s) | resolved rocks | '
              'false-alarm rate |' % '; '.join(h['height_classes']), '|---|---|---|---|---|']
    for b in h['by_altitude']:
        if b['maps']:
            lines.append('| %g-%g | %d | %s | %s | %s |' % (
                b['altitude_m'][0], b['altitude_m'][1], b['maps'],
                ' / '.join(fmt(p) for p in b['detection_probability_by_height']),
                ' / '.join(str(x) for x in b['rocks_resolved_by_height']),
                fmt(b['false_alarm_rate'])))
    a = h['all_maps']
    lines += ['', 'Every map together: P_d %s (%d of %d resolved rocks; by rock height %s), '
              'false-alarm rate %s (%d of %d rock-free cells).' % (
                  fmt(a['detection_probability']), sum(a['rocks_detected_by_height']),
                  sum(a['rocks_resolved_by_height']),
                  ' / '.join(fmt(p) for p in a['detection_probability_by_height']),
                  fmt(a['false_alarm_rate']), a['false_rock_cells'], a['rock_free_cells'])]
    sens = report['sensitivity']
    if sens['numeric'] or sens['choices']:
        lines += ['', '## Which dispersions go with the error', '',
                  'Spearman rank correlation of each dispersion with the run\'s pose RMS error '
                  'over %d runs (a screening aid, not a cause; |rho| below about %s is noise at '
                  'this size).' % (sens['runs'], fmt(sens['noise_level'], 2)), '',
                  '| dispersion | measured as | rho |', '|---|---|---|']
        for row in sens['numeric']:
            lines.append('| %s | %s | %s |' % (row['key'], row['measure'],
                                             fmt(row['spearman_rho'], 2)))
        for row in sens['choices']:
            lines.append('| %s | median pose RMS by value | %s |' % (row['key'], ', '.join(
                '%s: %s m (%d runs)' % (v, fmt(g['pose_rms_p50_m']), g['runs'])
                for v, g in row['values'].items())))
    lines += ['', '## Worst runs', '',
              'By final position error; each line is the one command that flies it again '
              '(it keeps the LCM log and checks the summary against the campaign\'s).', '']
    for w in report['worst_runs']:
        rep = reproduced.get(w['run'])
        lines.append('- run %d: %s, final error %s m, pose RMS %s m%s%s  \n  `%s`' % (
            w['run'], w['result'], fmt(w['final_position_error_m']),
            fmt(w['pose_rms_error_m']), (' (%s)' % w['reasons']) if w['reasons'] else '',
            '' if rep is None else ('; re-flown: summary identical' if rep
                                    else '; re-flown: SUMMARY DIFFERS'), w['reproduce']))
        if (worst_plots or {}).get(w['run']):
            lines.append('  plots of the re-flown run (swf-plot on its log): ' + ', '.join(
                '[%s](%s)' % (os.path.splitext(os.path.basename(p))[0], p)
                for p in worst_plots[w['run']]))
    if report['failed_runs']:
        lines += ['', 'Runs whose verdict was failed (their LCM logs are kept in the run '
                  'directories):', '']
        for r in report['failed_runs']:
            lines.append('- run %d: %s  \n  `%s`' % (r['run'], r['reasons'], r['reproduce']))
    lines += ['', '## Timing (measured; differs between machines and engines)', '',
              '| stage | p99 median over runs (ms) | p99 worst run (ms) | max (ms) |',
              '|---|---|---|---|']
    for name, s in sorted(t['stages'].items()):
        lines.append('| %s | %s | %s | %s |' % (name, fmt(s['p99_ms_median_over_runs']),
                                               fmt(s['p99_ms_worst_run']), fmt(s['max_ms'])))
    lines += ['', 'Frame-group overruns: %d (in %d runs). Hazard updates longer than their '
              'period (hazard_every frames): %d (in %d runs). Allocations after start: %d. Wall '
              'time per run: median %s s.' % (
                  t['overruns'], t['runs_with_overruns'], t['hazard_overruns'],
                  t['runs_with_hazard_overruns'], t['allocations_after_start'],
                  fmt(t['wall_s_per_run']['p50'])), '',
              'Lockstep runs go faster than the camera rate, so the frame group sometimes waits '
              'for the hazard group or the output thread to give a slot back (%d cycles, at most '
              '%s ms); that wait is the simulator\'s, and is left out of the stages and the '
              'overruns.' % (t['lockstep_wait_cycles'], fmt(t['lockstep_wait_max_ms'])), '']
    if pngs:
        lines += ['## Plots', ''] + ['![%s](%s)' % (p, p) for p in pngs] + ['']
    if report.get('plot_errors'):
        lines += ['## Plots not drawn', ''] + ['- %s' % e for e in report['plot_errors']] + ['']
    if worst_plots and report['worst_runs'] and worst_plots.get(report['worst_runs'][0]['run']):
        w = report['worst_runs'][0]['run']
        lines += ['## The worst run (%d), drawn by swf-plot from its log' % w, ''] + [
            '![%s](%s)' % (p, p) for p in worst_plots[w]] + ['']
    return '\n'.join(lines)


def write(out, spec, reproduced=None, with_plots=True, plot_tool=None):
    """Writes report.json and report.md (with the plots when with_plots; the worst re-flown runs'
    own plots too when plot_tool names swf-plot). Returns (report, the plots not drawn, why)."""
    report, outputs, edges, done = aggregate(out, spec)
    report['worst_reproduced'] = {str(k): v for k, v in sorted((reproduced or {}).items())}
    report_dir = os.path.join(out, 'report')
    os.makedirs(report_dir, exist_ok=True)
    pngs, worst_plots, errors = [], {}, []
    if with_plots and done:
        try:
            pngs = plots(report, outputs, edges, done, report_dir)
        except ImportError as e:
            # The report stands without its figures; the missing ones are named, not hidden.
            errors.append('the campaign plots were not drawn: %s (Debian: python3-matplotlib; '
                          'or run with the system /usr/bin/python3)' % e)
    if with_plots and plot_tool and reproduced:
        worst_plots, run_errors = run_plots(out, report, reproduced, report_dir, plot_tool)
        errors += run_errors
    report['plot_errors'] = errors
    engine.write_atomically(os.path.join(report_dir, 'report.json'),
                            json.dumps(report, indent=1, sort_keys=True, allow_nan=False) + '\n')
    engine.write_atomically(os.path.join(report_dir, 'report.md'),
                            markdown(report, pngs, reproduced or {}, worst_plots))
    return report, errors
