#!/usr/bin/env python3
"""The rule of issue 38 for one estimate against the simulation's truth.

usage: honesty.py POINTS TRUTH STDERR RULE
RULE: honest  - the ok points' sigmas honest (median |error|/sigma <= 1.5, <= 5 % beyond 3 sigma),
                every ok value finite, and no warning;
      handled - refused (no POINTS), or no ok point, or a warning on STDERR, or the ok points honest;
                never a non-finite ok value.
Exits 1 with the reason when the rule fails."""
import csv, math, os, sys

MAX_MEDIAN_RATIO = 1.5
MAX_BEYOND_3 = 0.05

points, truth, stderr, rule = sys.argv[1:5]
warned = os.path.exists(stderr) and 'warning:' in open(stderr).read()
if not os.path.exists(points):
    if rule == 'handled':
        sys.exit(0)
    sys.exit(f'{points}: no output')
est = list(csv.DictReader(open(points)))
tru = {r['id']: r for r in csv.DictReader(open(truth))}
ratios = []
for e in est:
    if e['status'] != 'ok':
        continue
    vals = [float(e[k]) for k in ('x', 'y', 'z', 'xc', 'yc', 'zc', 'sigma_zc')]
    if not all(math.isfinite(v) for v in vals):
        sys.exit(f"feature {e['id']}: ok with a non-finite value")
    t = tru[e['id']]
    if t['frame'] != e['frame']:
        continue  # truth in another frame (a shifted log): only the other rules apply
    ratios.append(abs(float(e['zc']) - float(t['zc'])) / float(e['sigma_zc']))
ratios.sort()
honest = not ratios or (ratios[len(ratios) // 2] <= MAX_MEDIAN_RATIO and
                        sum(r > 3 for r in ratios) <= MAX_BEYOND_3 * len(ratios))
summary = (f"{len(ratios)} ok, median ratio {ratios[len(ratios) // 2]:.2f}, "
           f"{100 * sum(r > 3 for r in ratios) / len(ratios):.1f} % beyond 3 sigma" if ratios else "no ok point")
if rule == 'honest':
    if not honest or warned:
        sys.exit(f"{points}: not honest or warned ({summary}, warned={warned})")
elif rule == 'handled':
    if not (honest or warned):
        sys.exit(f"{points}: confidently wrong ({summary}, no warning)")
else:
    sys.exit(f'unknown rule {rule}')
print(summary + (' (warned)' if warned else ''))
