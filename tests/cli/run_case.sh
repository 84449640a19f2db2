#!/usr/bin/env bash
# Runs one CLI test case: tests/cli/<tool>/<case>/ holds
#   cmd              a bash snippet, run in a fresh temporary folder (cwd) with the mvtm tools on
#                    PATH and $CASE (the case folder), $MVTM_DATA, $MVTM_SOURCE set
#   expected_status  the exit status it must end with
#   expected_stdout  (optional) exact expected standard output
#   expected_stderr  (optional) exact expected standard error
# A cmd that exits 77 is reported as skipped (e.g. real data not present).
set -u
case_dir=$1
bin_dir=$2
work=$(mktemp -d "${TMPDIR:-/tmp}/mvtm-cli.XXXXXX")
trap 'rm -rf "$work"' EXIT
export CASE=$case_dir PATH="$bin_dir:$PATH" LC_ALL=C
# The fixture generators (mkroad, mkvideo) are test scaffolding, not tools under test: the
# sanitizer pass points MVTM_FIXTURE_BIN at the uninstrumented ones (7x faster), except for the
# generators' own cases.
tool=$(basename "$(dirname "$case_dir")")
if [ -n "${MVTM_FIXTURE_BIN:-}" ] && [ "$tool" != mkroad ] && [ "$tool" != mkvideo ]; then
  export PATH="$MVTM_FIXTURE_BIN:$PATH"
fi
export MVTM_DATA=${MVTM_DATA:-$(cd "$(dirname "$0")/../../.." && pwd)/shared/data}
cd "$work" || exit 1
bash "$case_dir/cmd" >"$work/.stdout" 2>"$work/.stderr"
status=$?
[ "$status" = 77 ] && { echo "skipped: $(tail -1 "$work/.stderr")"; exit 77; }
fail=0
want=$(cat "$case_dir/expected_status")
if [ "$status" != "$want" ]; then
  echo "exit status $status, expected $want"; fail=1
fi
for s in stdout stderr; do
  if [ -f "$case_dir/expected_$s" ] && ! diff -u "$case_dir/expected_$s" "$work/.$s"; then
    echo "$s differs (above: - expected, + actual)"; fail=1
  fi
done
if [ $fail = 1 ]; then
  echo "--- stdout"; head -c 3000 "$work/.stdout"; echo "--- stderr"; head -c 3000 "$work/.stderr"
fi
exit $fail
