"""Diff two snapshots of scripts/metrics_snapshot.py with plain equality: exit 1 on any change."""

import json
import sys

a, b = (json.load(open(p)) for p in sys.argv[1:3])
bad = 0
for key in sorted(set(a) | set(b)):
    if key not in a or key not in b:
        print("only in one:", key)
        bad += 1
        continue
    if a[key] != b[key]:
        bad += 1
        ma, mb = a[key].get("metrics", a[key]), b[key].get("metrics", b[key])
        if isinstance(ma, dict) and isinstance(mb, dict):
            diffs = {k: (ma.get(k), mb.get(k)) for k in set(ma) | set(mb) if ma.get(k) != mb.get(k)}
            print(key, diffs or "events differ")
        else:
            print(key, ma, mb)
print(f"{len(a)} vs {len(b)} runs, {bad} differ")
sys.exit(1 if bad else 0)
