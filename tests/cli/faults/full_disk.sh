# Shared by the full_disk cases: run a tool whose outputs go to a tiny tmpfs (a full disk).
# The run must fail with one line naming a file and saying the disk is full, and every file left
# under a final name must equal the same file from a run with room (nothing truncated, nothing
# empty); no temporary may be left. Needs root (mount); exit 77 (skipped) otherwise.
#   full_disk_setup SIZE        mounts a tmpfs of SIZE on ./full
#   full_disk_check REF OUT     compares OUT (under full/) against REF, prints findings
full_disk_setup() {
  mkdir -p full
  mount -t tmpfs -o "size=$1" tmpfs full 2>/dev/null ||
    { echo "cannot mount a tmpfs here (not root?)" >&2; exit 77; }
  trap 'umount full' EXIT
}
full_disk_check() {
  local ref=$1 out=$2 n
  n=$(grep -c '' err)
  [ "$n" = 1 ] || echo "$n lines on stderr"
  grep -q 'No space left on device' err || echo "stderr does not say the disk is full"
  grep -q ": error: full/" err || echo "stderr does not name the output file"
  find "$out" -name '.*tmp-*' | grep -q . && echo "temporary files left"
  local kept=0
  while IFS= read -r f; do
    rel=${f#"$out"/}
    if cmp -s "$f" "$ref/$rel"; then kept=$((kept + 1)); else echo "differs from a full run: $rel"; fi
  done < <(find "$out" -type f ! -name '*.json' ! -name '*.tsv')
  echo "complete files kept: $([ $kept -gt 0 ] && echo some || echo none)"
}
