#!/usr/bin/env python3
"""Compare two `pf-viz report` summaries, ignoring what depends on measured time.

    scripts/compare-summaries.py A/summary.json B/summary.json [--only smooth,epf]

Two reports run with the same seed and scale must agree in every number except those their
`timing_dependent` key lists (JSON pointers into each section's result). Those pointers, from
either file, are removed from both before the comparison. Floats are compared exactly: the
engine is deterministic, so any difference is a change of result. Exits 0 when the summaries
agree, 1 with a list of differing paths when they do not, 2 on bad input. `--only` compares
just the named sections (for a report run with `pf-viz report --only`).
"""

import json
import sys


def unescape(token):
    return token.replace("~1", "/").replace("~0", "~")


def remove_pointer(doc, pointer):
    """Delete the value at a JSON pointer (RFC 6901) if it exists."""
    if not pointer.startswith("/"):
        return
    tokens = [unescape(t) for t in pointer[1:].split("/")]
    node = doc
    for t in tokens[:-1]:
        if isinstance(node, dict) and t in node:
            node = node[t]
        elif isinstance(node, list) and t.isdigit() and int(t) < len(node):
            node = node[int(t)]
        else:
            return
    last = tokens[-1]
    if isinstance(node, dict):
        node.pop(last, None)
    elif isinstance(node, list) and last.isdigit() and int(last) < len(node):
        node[int(last)] = None


def differences(a, b, path, out):
    if type(a) is not type(b):
        out.append(f"{path or '/'}: {json.dumps(a)[:80]} != {json.dumps(b)[:80]}")
    elif isinstance(a, dict):
        for k in sorted(set(a) | set(b)):
            p = f"{path}/{k}"
            if k not in a:
                out.append(f"{p}: only in the second")
            elif k not in b:
                out.append(f"{p}: only in the first")
            else:
                differences(a[k], b[k], p, out)
    elif isinstance(a, list):
        if len(a) != len(b):
            out.append(f"{path}: {len(a)} items != {len(b)}")
        for i, (x, y) in enumerate(zip(a, b)):
            differences(x, y, f"{path}/{i}", out)
    elif a != b:
        out.append(f"{path or '/'}: {json.dumps(a)[:80]} != {json.dumps(b)[:80]}")


def main(argv):
    only = None
    if len(argv) == 5 and argv[3] == "--only":
        only = set(argv[4].split(","))
        argv = argv[:3]
    if len(argv) != 3:
        print(
            "usage: compare-summaries.py A/summary.json B/summary.json [--only a,b]",
            file=sys.stderr,
        )
        return 2
    try:
        docs = [json.load(open(p, encoding="utf-8")) for p in argv[1:]]
    except (OSError, ValueError) as e:
        print(f"compare-summaries.py: {e}", file=sys.stderr)
        return 2
    timing = {}
    for d in docs:
        for section, pointers in d.get("timing_dependent", {}).items():
            timing.setdefault(section, set()).update(pointers)
    for d in docs:
        sections = d.get("sections", {})
        for section, pointers in timing.items():
            if section in sections:
                for p in pointers:
                    remove_pointer(sections[section], p)
        # The version may move between builds; everything else is the run's content.
        d.pop("version", None)
        d.pop("timing_dependent", None)
        if only is not None:
            d["sections"] = {k: v for k, v in sections.items() if k in only}
    out = []
    differences(docs[0], docs[1], "", out)
    if out:
        print(f"{len(out)} differences:")
        for line in out[:200]:
            print("  " + line)
        return 1
    print("summaries agree (timing-dependent numbers excluded)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
