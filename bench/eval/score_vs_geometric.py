#!/usr/bin/python3
"""Score the implicit methods of a real-rig evaluation (the output folder of `make eval` /
isokit-eval) against the best geometric method of each row, not only against dqs.

For every <rig>/<animation>.metrics.json that holds the geometric methods (dqs, ddm, cor by
default; those of them present) and an implicit method, each criterion of
../shared/tools/judge_vs_dqs.py (imported, so the criteria stay the shared script's) is applied
with each geometric method in the role of dqs. An implicit method meets a criterion against the
best geometric method when it meets it against every one of them: every bar of the judge grows
with the reference's value (overlap, self-intersections, inverted triangles, edge distortion
max and mean), so the best geometric method sets the strictest bar; the volume criterion's
"frames where the reference has no new self-intersection" then counts a frame as clean when any
geometric method is clean there. Criteria that do not depend on the reference (rest recovery on
bend-and-return rows, converged, speed at --ms) are the shared script's as they are.

Prints, per implicit method, the rows meeting each criterion out of the rows it applies to, the
rows meeting every criterion and the total of checks met; -v adds one line per row naming, per
failed criterion, the geometric methods that beat it. --json F writes the same as JSON.
The shared script stays the reference against dqs (../shared/tools/eval_score.py).

The judge applies `folds` and the skin's overlap wherever the metrics carry `folded_new` and
`skin_overlap_new`. `--judge old` scores the same files as the judge did before those fields
existed (they are left out: `inverted` and the whole mesh's overlap apply), so both judges can be
compared on one run. `--strip-to DIR` writes such a copy of the evaluation's metrics files, for
../shared/tools/eval_score.py.

The default method of isokit-skin, the add-on and isokit-batch is the implicit method the score
puts first (docs/decisions/default-method-follows-the-score.md): the last line says which method
has the highest total, and warns when the evaluation's `eval.json` names another default.
Usage: score_vs_geometric.py EVAL_DIR [--methods implicit2013 tracking2014] [--geometric dqs ddm cor]
                             [--ms 33] [--tools DIR] [--judge new|old] [--strip-to DIR] [-v] [--json F]"""
import argparse
import glob
import json
import os
import sys
import tempfile

ORDER = ['overlap', 'self_int', 'folds', 'inverted', 'edge_max', 'edge_mean', 'volume', 'rest', 'converged', 'speed']
IMPLICIT = ('implicit2013', 'tracking2014')  # the methods a default is chosen among
HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_TOOLS = os.path.normpath(os.path.join(HERE, '..', '..', '..', 'shared', 'tools'))


def load_judge(tools):
    """judge() of judge_vs_dqs.py in `tools`; exits 2 with one line when it is missing."""
    if not os.path.isfile(os.path.join(tools, 'judge_vs_dqs.py')):
        print(f"score_vs_geometric: {tools}/judge_vs_dqs.py not found; pass --tools DIR (the shared tools)",
              file=sys.stderr)
        sys.exit(2)
    sys.path.insert(0, tools)
    from judge_vs_dqs import judge  # noqa: E402
    return judge


# The fields the judge of issue 47 added: left out by `--judge old`.
NEW_JUDGE_FIELDS = ('folded_new', 'skin_overlap_new')


def strip_new_judge(doc):
    """A copy of a metrics document without the fields of the new judge (every frame and worst)."""
    d = dict(doc)
    d['methods'] = {}
    for name, m in doc.get('methods', {}).items():
        m = dict(m)
        m['frames'] = [{k: v for k, v in f.items() if k not in NEW_JUDGE_FIELDS} for f in m.get('frames', [])]
        if isinstance(m.get('worst'), dict):
            m['worst'] = {k: v for k, v in m['worst'].items() if k not in NEW_JUDGE_FIELDS}
        d['methods'][name] = m
    return d


def strip_copy(directory, dest):
    """Writes every <rig>/<animation>.metrics.json of `directory` under `dest`, stripped."""
    n = 0
    for path in sorted(glob.glob(os.path.join(directory, '*', '*.metrics.json'))):
        out = os.path.join(dest, os.path.relpath(path, directory))
        os.makedirs(os.path.dirname(out), exist_ok=True)
        with open(out, 'w') as f:
            json.dump(strip_new_judge(json.load(open(path))), f)
        n += 1
    return n


def judge_row(judge, doc, method, geometric, bend, ms, tmp):
    """{criterion: (ok, [geometric methods it fails against])} for one row and implicit method."""
    out = {}
    for g in geometric:
        d = dict(doc)
        d['methods'] = {'dqs': doc['methods'][g], method: doc['methods'][method]}
        path = os.path.join(tmp, f"{g}-{method}.json")
        with open(path, 'w') as f:
            json.dump(d, f)
        res, _ = judge(path, path, method, rest=bend, ms=ms)
        for k, (ok, _) in res.items():
            prev_ok, beaten_by = out.get(k, (True, []))
            out[k] = (prev_ok and ok, beaten_by + ([] if ok else [g]))
    return out


def score(directory, methods, geometric, ms, judge, verbose, old=False):
    rows = {m: [] for m in methods}
    with tempfile.TemporaryDirectory() as tmp:
        for path in sorted(glob.glob(os.path.join(directory, '*', '*.metrics.json'))):
            doc = json.load(open(path))
            if old:
                doc = strip_new_judge(doc)
            present = [g for g in geometric if g in doc.get('methods', {})]
            if not present:
                continue
            name = os.path.relpath(path, directory)[:-len('.metrics.json')]
            bend = str(doc.get('animation', '')).startswith('bend') or os.path.basename(name) == 'bend'
            for m in methods:
                if m not in doc['methods']:
                    continue
                res = judge_row(judge, doc, m, present, bend, ms, tmp)
                rows[m].append({'row': name, 'geometric': present,
                                'criteria': {k: ok for k, (ok, _) in res.items()},
                                'beaten_by': {k: by for k, (_, by) in res.items() if by},
                                'all': all(ok for ok, _ in res.values())})
                if verbose:
                    fails = '; '.join(f"{k} (by {', '.join(by)})" for k, (ok, by) in res.items() if not ok)
                    print(f"{name} {m}: " + ('ok' if not fails else 'FAIL: ' + fails))
    return rows


def summarise(rows):
    table = {}
    for k in ORDER:
        app = [r for r in rows if k in r['criteria']]
        if app:
            table[k] = [sum(r['criteria'][k] for r in app), len(app)]
    return table


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('dir')
    ap.add_argument('--methods', nargs='+', default=['implicit2013', 'tracking2014'])
    ap.add_argument('--geometric', nargs='+', default=['dqs', 'ddm', 'cor'])
    ap.add_argument('--ms', type=float, default=33.0)
    ap.add_argument('--tools', default=DEFAULT_TOOLS, help='folder of judge_vs_dqs.py (default ../shared/tools)')
    ap.add_argument('--judge', choices=['new', 'old'], default='new',
                    help='old: leave out folded_new and skin_overlap_new (the judge before them)')
    ap.add_argument('--strip-to', default=None,
                    help='write the metrics files without the new judge\'s fields into this folder, then exit')
    ap.add_argument('-v', action='store_true')
    ap.add_argument('--json', default=None)
    a = ap.parse_args()
    if a.strip_to:
        print(f"wrote {strip_copy(a.dir, a.strip_to)} metrics files without {', '.join(NEW_JUDGE_FIELDS)} "
              f"to {a.strip_to}")
        return
    judge = load_judge(a.tools)
    rows = score(a.dir, a.methods, a.geometric, a.ms, judge, a.v, old=a.judge == 'old')
    if not any(rows.values()):
        print(f"no metrics files with {' / '.join(a.geometric)} and {' / '.join(a.methods)} under {a.dir}")
        sys.exit(2)
    report = {}
    for m, rs in rows.items():
        if not rs:
            continue
        table = summarise(rs)
        passed = sum(r['all'] for r in rs)
        print(f"{m} vs the best of {', '.join(a.geometric)}: " +
              ' '.join(f"{k} {p}/{n}" for k, (p, n) in table.items()))
        print(f"  {passed} of {len(rs)} rows meet every criterion "
              f"({sum(p for p, _ in table.values())} of {sum(n for _, n in table.values())} criterion checks)")
        report[m] = {'rows': rs, 'criteria': table, 'passed': passed, 'total': len(rs)}
    implicit = [m for m in report if m in IMPLICIT]
    first = max(implicit, key=lambda m: sum(p for p, _ in report[m]['criteria'].values()), default=None)
    if first:
        print(f"first by the total against the best geometric method ({a.judge} judge): {first}")
        default = read_default_method(a.dir)
        if default and default != first and a.judge == 'new':
            print(f"warning: isokit's default method is {default}, but the score puts {first} first; "
                  f"change kDefaultMethod (apps/skinning/lib/include/isokit/skinning/pipeline.h)")
    if a.json:
        with open(a.json, 'w') as f:
            json.dump({'geometric': a.geometric, 'judge': a.judge, 'first': first, 'methods': report}, f,
                      indent=1)


def read_default_method(directory):
    """The default method the evaluation's binary had (eval.json's `default_method`), or None."""
    try:
        return json.load(open(os.path.join(directory, 'eval.json'))).get('default_method')
    except (OSError, ValueError):
        return None


if __name__ == '__main__':
    main()
