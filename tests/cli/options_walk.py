#!/usr/bin/env python3
"""Walks a tool's declared option table: every option that changes output, changed alone, redoes
the outputs, which then equal a fresh run's with that option byte for byte; a rerun redoes
nothing; a cosmetic option redoes nothing.

usage: options_walk.py BIN_DIR TOOL [SPECS.json]

The tool's table comes from `TOOL --options-json` (the same table --help, the checks and the
provenance come from), so a new option cannot escape the walk: an option the spec does not know
how to vary fails the test. SPECS (tests/cli/options_walk.json) gives per tool:
  setup     shell commands run once in a scratch folder (a small fixture)
  cmd       the base command (run in a copy of the setup)
  outputs   folders/files under the run folder whose files are compared (provenance/*.json left
            out: they hold times)
  args      per flag, the extra arguments that vary it when its declared alternative alone does
            not do (e.g. a file, or a companion option); "" skips the flag, with
  why       per skipped flag, the reason (a skipped flag without a reason fails)
  kept      per output folder/file, the flags that do not change it: changed alone, such a flag
            must leave it untouched (and redo the others); the byte-for-byte comparison with a
            fresh run then checks that it indeed does not depend on the flag (dynmask's maps
            and its tracking options)
  session   (simulate) the tool runs a session, not outputs kept up to date: every run makes
            its files anew. Walked instead: the base run's record (the file `record` names, e.g.
            rec/summary.json) lists exactly the options --help shows, and every option changed
            alone runs and is recorded with its new value (the record says what the session
            ran with).
"Redone" means every output file was rewritten (its modification time changed) or the set of
files changed; "nothing redone" means no output file was touched.
"""
import filecmp
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile

bin_dir, tool = sys.argv[1], sys.argv[2]
specs_path = sys.argv[3] if len(sys.argv) > 3 else os.path.join(
    os.path.dirname(os.path.abspath(__file__)), "options_walk.json")
specs = json.load(open(specs_path))
if tool not in specs:
    print(f"{tool}: no entry in {specs_path}: every tool's options are walked")
    sys.exit(1)
spec = specs[tool]
env = dict(os.environ, PATH=bin_dir + os.pathsep + os.environ["PATH"], LC_ALL="C")
table = json.loads(subprocess.run([os.path.join(bin_dir, tool), "--options-json"],
                                  capture_output=True, text=True, check=True, env=env).stdout)
scratch = tempfile.mkdtemp(prefix="mvtm-walk-")
failures = []


def sh(cmd, cwd):
    r = subprocess.run(cmd, shell=True, cwd=cwd, env=env, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"`{cmd}` exited {r.returncode}: {r.stderr.strip()[-400:]}")
    return r


def files(run):
    """Output files under `run` → modification time (provenance records left out)."""
    out = {}
    for o in spec["outputs"]:
        p = os.path.join(run, o)
        walk = [(os.path.dirname(p), [], [os.path.basename(p)])] if os.path.isfile(p) else os.walk(p)
        for d, _, fs in walk:
            for f in fs:
                full = os.path.join(d, f)
                rel = os.path.relpath(full, run)
                if f.startswith(".") or (rel.split(os.sep)[-2:-1] == ["provenance"] and
                                         f.endswith(".json")):
                    continue
                out[rel] = os.stat(full).st_mtime_ns
    return out


def variant_args(opt):
    flag = opt["flag"]
    if flag in spec.get("args", {}):
        return spec["args"][flag]
    alt = opt["alternative"]
    if alt == "":
        return None
    if opt["type"] == "FLAG":
        return flag if alt == "1" else None
    return f"{flag} {shlex.quote(alt)}"


def fresh(name):
    d = os.path.join(scratch, name)
    shutil.copytree(os.path.join(scratch, "setup"), d, symlinks=True)
    return d


os.makedirs(os.path.join(scratch, "setup"))
for c in spec["setup"]:
    sh(c, os.path.join(scratch, "setup"))
base = fresh("base")
sh(spec["cmd"], base)
base_files = files(base)
if not base_files:
    failures.append("the base command wrote no output file")

# The record lists exactly the options --help shows (positionals by their lower-case name).
helptext = sh(f"{tool} --help", base).stdout
shown, section = set(), ""
for line in helptext.splitlines():
    if line and not line[0].isspace():
        section = line.strip()
        continue
    m = re.match(r"^\s+(?:-\w,)?--([a-z0-9][a-z0-9-]*)", line)
    if m and m.group(1) not in ("help", "version"):
        shown.add(m.group(1).replace("-", "_"))
    m = re.match(r"^\s+([A-Z][A-Z0-9_]*)\b", line)
    if m and section.startswith("Positionals"):
        shown.add(m.group(1).lower())
records = [os.path.join(d, f) for d, _, fs in os.walk(base) for f in fs
           if f == tool + ".json" and os.path.basename(d) == "provenance"]
if spec.get("session"):
    records = [os.path.join(base, spec["record"])] if os.path.isfile(
        os.path.join(base, spec["record"])) else []
if not records:
    failures.append(f"the base command wrote no provenance/{tool}.json")
for r in records:
    keys = set(json.load(open(r))["options"])
    if keys != shown:
        failures.append(f"{os.path.relpath(r, base)}: options {sorted(keys - shown)} are not in "
                        f"--help, {sorted(shown - keys)} of --help are not in the record")

walked = 0
for opt in table["options"]:
    flag = opt["flag"]
    if opt["positional"] or flag in ("--force", "--frames", "--shard", "--help"):
        continue
    args = variant_args(opt)
    if args == "" and flag in spec.get("args", {}):
        if not spec.get("why", {}).get(flag):
            failures.append(f"{flag}: skipped without a reason in the spec")
        continue
    if args is None:
        failures.append(f"{flag}: no alternative value declared and none in the spec")
        continue
    cmd = spec["cmd"] + " " + args
    if spec.get("session"):
        run = fresh("opt" + flag.replace("-", "_"))
        try:
            sh(cmd, run)
            key = flag[2:].replace("-", "_")
            was = json.load(open(records[0]))["options"].get(key)
            now = json.load(open(os.path.join(run, spec["record"])))["options"].get(key)
            if now == was:
                failures.append(f"{flag}: changed to {args!r}, the record still says {now!r}")
        except (RuntimeError, OSError, KeyError, ValueError) as e:
            failures.append(f"{flag}: {e}")
        shutil.rmtree(run)
        walked += 1
        continue
    run = os.path.join(scratch, "opt" + flag.replace("-", "_"))
    shutil.copytree(base, run, symlinks=True)  # keeps modification times
    before = files(run)
    try:
        sh(cmd, run)
    except RuntimeError as e:
        failures.append(f"{flag}: {e}")
        continue
    after = files(run)
    if opt["changes_output"]:
        kept_under = [k for k, flags in spec.get("kept", {}).items() if flag in flags]
        is_kept = lambda f: any(f == k or f.startswith(k + "/") for k in kept_under)
        redo = [f for f in before if not is_kept(f)]
        touched = set(after) != set(before) or all(after[f] != before[f] for f in redo)
        if not touched:
            stale = [f for f in redo if after.get(f) == before[f]]
            failures.append(f"{flag}: changed to {args!r}, yet {len(stale)} of {len(redo)} "
                            f"outputs were not redone (e.g. {stale[0]})")
        rewritten = [f for f in before if is_kept(f) and after.get(f) != before[f]]
        if rewritten:
            failures.append(f"{flag}: changed to {args!r}, it redid {len(rewritten)} outputs "
                            f"that do not depend on it (e.g. {rewritten[0]})")
        ref = fresh("ref" + flag.replace("-", "_"))
        sh(cmd, ref)
        ref_files = files(ref)
        # Outputs under other names (--exr: NAME.exr beside NAME.png) stay; the fresh run's must
        # all be there.
        if not set(ref_files) <= set(after):
            failures.append(f"{flag}: the rerun lacks files a fresh run makes: "
                            f"{sorted(set(ref_files) - set(after))[:3]}")
        for f in sorted(set(ref_files) & set(after)):
            if not filecmp.cmp(os.path.join(ref, f), os.path.join(run, f), shallow=False):
                failures.append(f"{flag}: {f} differs from a fresh run's with {args!r}")
                break
        again_before = files(run)
        sh(cmd, run)
        again = files(run)
        redone = [f for f in again if again_before.get(f) != again[f]]
        if redone:
            failures.append(f"{flag}: an unchanged rerun redid {len(redone)} outputs")
        shutil.rmtree(ref)
    else:
        redone = [f for f in after if before.get(f) != after[f]]
        if redone:
            failures.append(f"{flag} (cosmetic): changed to {args!r}, it redid {len(redone)} "
                            f"outputs (e.g. {redone[0]})")
    shutil.rmtree(run)
    walked += 1

shutil.rmtree(scratch)
for f in failures:
    print(f)
print(f"{tool}: {walked} options walked, {len(failures)} failures")
sys.exit(1 if failures else 0)
