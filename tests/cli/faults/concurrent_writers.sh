# Shared by the concurrent_writers cases: several identical runs of a tool at the same moment
# into one output folder. Each must exit 0; every file under a final name must equal the same
# file from a single run (JSON provenance records apart from when things were written); no temporary may
# be left. A record's "time" and its outputs' "mtime_ns" are when they were written, so they are
# left out of the comparison, and so is "racy" (whether an input was written within 2 s of the
# run that recorded it).
#   run_at_once N COMMAND...   starts N copies of COMMAND together (released at once by a
#                              barrier) and waits for all; prints their exit statuses, their
#                              stderr, and whether the runs overlapped in time
#   same_as_one_run REF OUT    compares the files under OUT against those under REF (a single
#                              run's), prints findings
run_at_once() {
  local n=$1 i latest=0 earliest=0 s e statuses=""
  local -a pids
  shift
  rm -f go
  for ((i = 1; i <= n; i++)); do
    (
      while [ ! -e go ]; do sleep 0.005; done
      date +%s%N >"start$i"
      "$@" 2>"err$i"
      status=$?
      date +%s%N >"end$i"
      exit $status
    ) &
    pids[i]=$!
  done
  touch go
  for ((i = 1; i <= n; i++)); do
    wait "${pids[i]}"
    statuses="$statuses $?"
  done
  echo "$n runs at once, exit statuses:$statuses"
  for ((i = 1; i <= n; i++)); do
    sed "s/^/run $i: /" "err$i"
    s=$(cat "start$i") e=$(cat "end$i")
    [ "$s" -gt "$latest" ] && latest=$s
    { [ "$earliest" = 0 ] || [ "$e" -lt "$earliest" ]; } && earliest=$e
  done
  # Every run started before any ended: they all wrote at the same time.
  [ "$latest" -lt "$earliest" ] && echo "the runs overlapped" || echo "the runs did not overlap"
}
strip_times() {
  "${MVTM_PYTHON:-/usr/bin/python3}" -c '
import json, sys
def strip(v):
    if isinstance(v, dict):
        return {k: strip(x) for k, x in v.items() if k not in ("time", "mtime_ns", "racy")}
    if isinstance(v, list):
        return [strip(x) for x in v]
    return v
print(json.dumps(strip(json.load(open(sys.argv[1]))), sort_keys=True, indent=1))' "$1"
}
same_as_one_run() {
  local ref=$1 out=$2 n=0 bad=0 f
  (cd "$ref" && find . -type f | sort) >want
  (cd "$out" && find . -type f ! -name '.*' | sort) >got
  cmp -s want got || { echo "different file lists:"; diff want got; }
  while IFS= read -r f; do
    n=$((n + 1))
    if [ "${f%.json}" != "$f" ]; then
      cmp -s <(strip_times "$ref/$f") <(strip_times "$out/$f")
    else
      cmp -s "$ref/$f" "$out/$f"
    fi || { echo "differs from one run's: $f"; bad=$((bad + 1)); }
  done <want
  echo "$out: files $n, differing from one run's $bad, temporaries $(find "$out" -name '.*tmp-*' | wc -l)"
}
