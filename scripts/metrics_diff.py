"""Diff two snapshots of scripts/metrics_snapshot.py with plain equality: exit 1 on any change."""

import argparse
import json
import sys

ap = argparse.ArgumentParser(description=__doc__)
ap.add_argument("old", metavar="OLD.json")
ap.add_argument("new", metavar="NEW.json")
args = ap.parse_args()
try:
    a, b = (json.load(open(p)) for p in (args.old, args.new))
except (OSError, ValueError) as e:
    ap.error(f"cannot read a snapshot: {e}")
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
