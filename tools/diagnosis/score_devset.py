#!/usr/bin/env python3
"""Score `rigctl diagnose` on the diagnosis development set from its truth.

Runs the program as shipped (`rigctl diagnose --rig R --data RUN --json OUT
--quiet`, from the repository root so the rigs' default configs are found)
over every run of the set and scores the verdicts against `truth.json`:

* top-1 on single effects: the first named cause is the true one;
* two-effect recall: of the true causes of the pair runs, how many are
  among the named causes (and how many pairs have both);
* clean runs accused: a clean run (truth `none`) with any cause named;
* the same per rig, the confusion matrix (true cause x first named cause,
  single-effect and clean runs), the wall time per run, and one line per
  miss saying what was named instead and where the diagnosis put the
  misfit.

Writes `score.json` and `score.md` into --out (with the diagnoses' JSON in
`--out/json/`). The set (tests/data/diagnosis-devset by default) holds the
runs as `runs/case_NNN.csv.xz` or `.csv`; compressed ones are unpacked into
a temporary directory. Python 3 standard library only.

Usage:
  tools/diagnosis/score_devset.py --rigctl build/rigctl --out /tmp/devset
  tools/diagnosis/score_devset.py --out /tmp/devset --score-only   # re-score existing JSON
  options: --set DIR, --jobs N (runs diagnosed at a time, default 1: each
  run's wall time is then what a user at the rig waits), --cases case_001,...,
  --rig quarter_car, --timeout S (per run, default 1800)
"""
import argparse
import concurrent.futures
import json
import lzma
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DEFAULT_SET = os.path.join(REPO, 'tests', 'data', 'diagnosis-devset')


def run_path(set_dir, case, tmp):
    """The run file of `case`, unpacked into `tmp` when compressed."""
    plain = os.path.join(set_dir, 'runs', case + '.csv')
    if os.path.exists(plain):
        return plain
    packed = plain + '.xz'
    if not os.path.exists(packed):
        raise FileNotFoundError('no run file for %s in %s/runs (.csv or .csv.xz)' % (case, set_dir))
    out = os.path.join(tmp, case + '.csv')
    with lzma.open(packed) as src, open(out, 'wb') as dst:
        shutil.copyfileobj(src, dst)
    return out


def diagnose(rigctl, case, truth, set_dir, json_dir, tmp, timeout):
    """One diagnosis; returns (case, seconds, error text or None)."""
    data = run_path(set_dir, case, tmp)
    out = os.path.join(json_dir, case + '.json')
    cmd = [rigctl, 'diagnose', '--rig', truth['rig'], '--data', data, '--json', out, '--quiet']
    t0 = time.monotonic()
    try:
        p = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, timeout=timeout)
        err = None if p.returncode == 0 else 'exit %d: %s' % (p.returncode, p.stderr.strip()[-300:])
    except subprocess.TimeoutExpired:
        err = 'timeout after %d s' % timeout
    except OSError as e:  # the binary went away (a rebuild): this run fails, the others go on
        err = 'cannot run %s: %s' % (rigctl, e)
    secs = time.monotonic() - t0
    if data.startswith(tmp):
        os.remove(data)
    with open(os.path.join(json_dir, case + '.seconds'), 'w') as f:
        f.write('%.1f\n' % secs)
    return case, secs, err


def kind(truth):
    causes = truth['causes']
    if causes == ['none']:
        return 'clean'
    return 'single' if len(causes) == 1 else 'pair'


def where_text(d):
    """One phrase for where the diagnosis put the misfit (the 'where' of docs/diagnosis.md)."""
    w = d.get('where') or {}
    if not w.get('place'):
        return ''
    regs = ', '.join('%s %+.3g' % (r['feature'], r['coefficient']) for r in w.get('regressors', [])[:2])
    return 'where: %s (%.0f %% of the residual%s)' % (w['place'], 100.0 * w.get('explained_share', 0.0),
                                                       '; ' + regs if regs else '')


def form_text(truth):
    parts = []
    for cause in truth['causes']:
        e = truth.get('effects', {}).get(cause, {})
        form = e.get('model') or e.get('shape')
        ch = e.get('channels')
        parts.append(cause + (' (' + form + (' on ' + ','.join(ch) if ch else '') + ')' if form else ''))
    return ' + '.join(parts)


def score(truths, json_dir):
    """The figures and the miss list from the diagnoses in json_dir."""
    rows = []
    for case in sorted(truths):
        t = truths[case]
        path = os.path.join(json_dir, case + '.json')
        d = None
        if os.path.exists(path):
            with open(path) as f:
                d = json.load(f)
        secs = None
        sp = os.path.join(json_dir, case + '.seconds')
        if os.path.exists(sp):
            with open(sp) as f:
                secs = float(f.read())
        named = [c['cause'] for c in d['causes']] if d else []
        rows.append({'case': case, 'rig': t['rig'], 'kind': kind(t), 'truth': t['causes'],
                     'strength': t.get('strength', '-'), 'form': form_text(t), 'named': named,
                     'top': d['cause'] if d else 'error', 'unexplained': bool(d and d.get('unexplained')),
                     'where': where_text(d) if d else '', 'seconds': secs, 'missing': d is None})

    def figures(every):
        # A run with no diagnosis (failed, timed out, or not run yet) is
        # counted apart, not as a miss: a partial scoring stays readable.
        sel = [r for r in every if not r['missing']]
        single = [r for r in sel if r['kind'] == 'single']
        pairs = [r for r in sel if r['kind'] == 'pair']
        clean = [r for r in sel if r['kind'] == 'clean']
        top1 = sum(1 for r in single if r['top'] == r['truth'][0])
        found = sum(sum(1 for c in r['truth'] if c in r['named']) for r in pairs)
        both = sum(1 for r in pairs if all(c in r['named'] for c in r['truth']))
        accused = sum(1 for r in clean if r['named'])
        unexplained = [r for r in sel if r['unexplained']]
        secs = [r['seconds'] for r in sel if r['seconds'] is not None]
        return {'single': len(single), 'top1': top1, 'pairs': len(pairs), 'pair_causes': 2 * len(pairs),
                'pair_causes_found': found, 'pairs_both': both, 'clean': len(clean), 'clean_accused': accused,
                'unexplained': len(unexplained),
                'unexplained_without_where': sum(1 for r in unexplained if not r['where']),
                'median_s': statistics.median(secs) if secs else None, 'max_s': max(secs) if secs else None,
                'over_60_s': sum(1 for s in secs if s > 60.0), 'runs': len(every),
                'not_diagnosed': sum(1 for r in every if r['missing'])}

    rigs = sorted({r['rig'] for r in rows})
    result = {'all': figures(rows), 'per_rig': {rig: figures([r for r in rows if r['rig'] == rig]) for rig in rigs}}
    confusion = {}
    for r in rows:
        if r['kind'] in ('single', 'clean') and not r['missing']:
            got = r['top'] + (' (unexplained)' if r['unexplained'] else '')
            confusion.setdefault(r['truth'][0], {}).setdefault(got, 0)
            confusion[r['truth'][0]][got] += 1
    result['confusion'] = confusion
    misses = []
    for r in rows:
        if r['missing']:
            continue
        ok = {'single': r['top'] == r['truth'][0], 'clean': not r['named'],
              'pair': all(c in r['named'] for c in r['truth'])}[r['kind']]
        if ok:
            continue
        got = ', '.join(r['named']) if r['named'] else ('none, unexplained' if r['unexplained'] else 'none')
        line = '%s %s: %s [%s] -> %s' % (r['case'], r['rig'], r['form'] or 'clean', r['strength'], got)
        if r['where']:
            line += '; ' + r['where']
        misses.append(line)
    result['misses'] = misses
    result['not_diagnosed'] = [r['case'] for r in rows if r['missing']]
    result['runs'] = rows
    return result


def pct(a, b):
    return '%d/%d (%.0f %%)' % (a, b, 100.0 * a / b) if b else '-'


def markdown(result, command):
    lines = ['# Diagnosis development set: score', '', 'Command: `%s`' % command, '',
             '| rig | runs diagnosed | top-1 single | pair causes found | pairs with both | clean accused '
             '| unexplained (without where) | median s | max s | > 60 s |', '|---|---|---|---|---|---|---|---:|---:|---:|']
    for name, f in [('all', result['all'])] + sorted(result['per_rig'].items()):
        lines.append('| %s | %d/%d | %s | %s | %s | %s | %d (%d) | %s | %s | %d |' % (
            name, f['runs'] - f['not_diagnosed'], f['runs'], pct(f['top1'], f['single']), pct(f['pair_causes_found'], f['pair_causes']),
            pct(f['pairs_both'], f['pairs']), pct(f['clean_accused'], f['clean']), f['unexplained'],
            f['unexplained_without_where'], '%.1f' % f['median_s'] if f['median_s'] is not None else '-',
            '%.1f' % f['max_s'] if f['max_s'] is not None else '-', f['over_60_s']))
    lines += ['', '## Confusion (true cause -> first named cause; single-effect and clean runs)', '',
              '| true | named |', '|---|---|']
    for true, got in sorted(result['confusion'].items()):
        lines.append('| %s | %s |' % (true, ', '.join('%s x%d' % (g, n) for g, n in sorted(got.items()))))
    lines += ['', '## Misses', '']
    lines += ['* ' + m for m in result['misses']] or ['none']
    if result['not_diagnosed']:
        lines += ['', 'Not diagnosed (failed, timed out or not run): ' + ', '.join(result['not_diagnosed'])]
    return '\n'.join(lines) + '\n'


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--rigctl', default=os.path.join(REPO, 'build', 'rigctl'))
    ap.add_argument('--set', default=DEFAULT_SET, help='the set: truth.json and runs/ (default: %(default)s)')
    ap.add_argument('--out', required=True, help='directory for the diagnoses and the score')
    ap.add_argument('--jobs', type=int, default=1, help='runs diagnosed at a time (default 1)')
    ap.add_argument('--cases', default='', help='comma-separated case ids (default: all)')
    ap.add_argument('--rig', default='', help='only this rig')
    ap.add_argument('--timeout', type=float, default=1800.0, help='per run [s]')
    ap.add_argument('--score-only', action='store_true', help='score the JSON already in --out')
    a = ap.parse_args()

    with open(os.path.join(a.set, 'truth.json')) as f:
        truths = json.load(f)
    if a.cases:
        want = set(a.cases.split(','))
        unknown = want - set(truths)
        if unknown:
            sys.exit('score_devset: no such case in %s/truth.json: %s' % (a.set, ', '.join(sorted(unknown))))
        truths = {k: v for k, v in truths.items() if k in want}
    if a.rig:
        truths = {k: v for k, v in truths.items() if v['rig'] == a.rig}
    json_dir = os.path.join(a.out, 'json')
    os.makedirs(json_dir, exist_ok=True)
    command = ' '.join([os.path.relpath(sys.argv[0], REPO)] + sys.argv[1:])
    if not a.score_only:
        if not os.access(a.rigctl, os.X_OK):
            sys.exit('score_devset: %s is not an executable rigctl (build it or pass --rigctl)' % a.rigctl)
        tmp = tempfile.mkdtemp(prefix='devset_')
        try:
            with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, a.jobs)) as pool:
                futs = [pool.submit(diagnose, os.path.abspath(a.rigctl), c, truths[c], a.set, json_dir, tmp, a.timeout)
                        for c in sorted(truths)]
                for fut in concurrent.futures.as_completed(futs):
                    case, secs, err = fut.result()
                    print('%s %s %.1f s%s' % (case, truths[case]['rig'], secs, ' ERROR ' + err if err else ''),
                          flush=True)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
    result = score(truths, json_dir)
    result['command'] = command
    with open(os.path.join(a.out, 'score.json'), 'w') as f:
        json.dump(result, f, indent=1)
    md = markdown(result, command)
    with open(os.path.join(a.out, 'score.md'), 'w') as f:
        f.write(md)
    print(md)


if __name__ == '__main__':
    main()
