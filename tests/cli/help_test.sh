#!/bin/sh
# CLI habits (issue 21): `kuavo --help`, `kuavo help CMD` and `kuavo CMD --help` print the usage
# on stdout and exit 0; an unknown command or option prints the usage on stderr and exits 2.
set -u
kuavo=$1
dir=$2
rm -rf "$dir"
mkdir -p "$dir"
fail() { echo "FAIL: $*" >&2; exit 1; }
# expect CODE STDOUT_PATTERN STDERR_PATTERN ARGS...: exit code and a line in each stream.
expect() {
  code=$1 out=$2 err=$3
  shift 3
  "$kuavo" "$@" > "$dir/out" 2> "$dir/err"
  got=$?
  [ "$got" -eq "$code" ] || fail "kuavo $*: exit $got, expected $code"
  [ -z "$out" ] || grep -q -- "$out" "$dir/out" || fail "kuavo $*: no '$out' on stdout: $(head -c 300 "$dir/out")"
  [ -z "$err" ] || grep -q -- "$err" "$dir/err" || fail "kuavo $*: no '$err' on stderr: $(head -c 300 "$dir/err")"
  if [ "$code" -eq 0 ]; then [ ! -s "$dir/err" ] || fail "kuavo $*: wrote to stderr: $(head -c 300 "$dir/err")"; fi
  if [ "$code" -ne 0 ]; then [ ! -s "$dir/out" ] || fail "kuavo $*: wrote to stdout on error"; fi
}

expect 0 "usage: kuavo <command>" "" --help
expect 0 "usage: kuavo <command>" "" -h
expect 0 "usage: kuavo <command>" "" help
expect 2 "" "usage: kuavo <command>"
expect 2 "" "unknown command 'dance'" dance
expect 2 "" "usage: kuavo <command>" dance
expect 2 "" "unknown command 'nope'" help nope
for cmd in demo paper replay retarget retarget-sweep simulate campaign model; do
  grep -q "  $cmd " "$dir/err" || "$kuavo" --help | grep -q "^  $cmd " || fail "kuavo --help does not list $cmd"
  expect 0 "usage: kuavo $cmd" "" help "$cmd"
  cp "$dir/out" "$dir/help_$cmd"
  expect 0 "usage: kuavo $cmd" "" "$cmd" --help
  cmp -s "$dir/out" "$dir/help_$cmd" || fail "kuavo $cmd --help differs from kuavo help $cmd"
  # --help after other arguments still only prints the usage (nothing runs, nothing is written).
  expect 0 "usage: kuavo $cmd" "" "$cmd" --out "$dir/never" --help
  [ ! -e "$dir/never" ] || fail "kuavo $cmd --out DIR --help ran the command"
  expect 2 "" "usage: kuavo $cmd" "$cmd" --no-such-option
done
expect 2 "" "usage: kuavo replay" replay --out "$dir/r"
# A number option out of its range, or given to a stage it does not apply to, is refused by name.
expect 2 "" "support-margin" retarget -o "$dir/never.motion" --support-margin 0.05
expect 2 "" "support-margin" retarget -o "$dir/never.motion" --stage geometric --support-margin 0.01
[ ! -e "$dir/never.motion" ] || fail "kuavo retarget wrote a motion with a refused --support-margin"
expect 2 "" "no such file" demo "$dir/missing.bvh" --out "$dir/never"
[ ! -e "$dir/never" ] || fail "kuavo demo with a missing BVH made its report folder"
# A run piped or with --quiet shows no progress line (no carriage return); --quiet also drops the
# summary lines: nothing on stdout, the motion written.
"$kuavo" retarget --stage geometric -o "$dir/q.motion" --quiet > "$dir/out" 2> "$dir/err" || fail "retarget --quiet failed"
[ ! -s "$dir/out" ] && [ ! -s "$dir/err" ] || fail "retarget --quiet printed: $(head -c 300 "$dir/out" "$dir/err")"
[ -s "$dir/q.motion" ] || fail "retarget --quiet wrote no motion"
"$kuavo" retarget --stage geometric -o "$dir/q.motion" > "$dir/out" 2> "$dir/err" || fail "retarget failed"
grep -q "kuavo retarget:" "$dir/out" || fail "retarget printed no summary"
if tr -d '\n' < "$dir/err" | grep -q "$(printf '\r')"; then fail "a piped retarget drew a progress line"; fi
echo "PASS"
