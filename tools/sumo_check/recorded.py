"""SUMO's runs recorded in an earlier --json, reused where only mapc changed (--sumo-runs)."""
import json
import sys


def reuse(path, digest_field, digest, runs_field, seeds, what):
    """The runs under `runs_field` of the --json at `path`, if it was recorded for the same SUMO inputs (its
    `digest_field` equals `digest`) and the same seeds; the tool stops with a message otherwise."""
    with open(path) as f:
        old = json.load(f)
    if old.get(digest_field) != digest:
        sys.exit("sumo_check: %s was recorded for other SUMO inputs (%s); run SUMO again" % (path, what))
    runs = old[runs_field]
    if [r["seed"] for r in runs] != list(seeds):
        sys.exit("sumo_check: %s has SUMO runs for other seeds" % path)
    print("  SUMO: %d seeds reused from %s (same %s)" % (len(runs), path, what), file=sys.stderr)
    return runs
