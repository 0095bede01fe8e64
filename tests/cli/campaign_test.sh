#!/bin/sh
# A small campaign (1 motion × 1 ground × 2 perturbation sets × 2 seeds, 0.6 s runs with a
# random push) run twice: the two tables are the same file, every run finished, the
# perturbed runs differ from the unperturbed ones, and a resumed campaign redoes only the
# run that was removed and gives the same table again. The second campaign reuses the first
# one's built-in dance motion (`kuavo retarget` with its closed-loop check: ~4 min in CI);
# the offline stage's own determinism is checked by retargeting twice without the check.
set -eu
kuavo=$1
dir=$2
rm -rf "$dir"
mkdir -p "$dir"
cat > "$dir/spec.json" <<'SPEC'
{"name": "ci", "motions": ["dance"], "grounds": ["floor"], "perturbations": ["none", "show"], "seeds": 2,
 "duration_s": 0.6, "push": {"impulse_Ns": 10.0, "duration_s": 0.1, "start_after_s": 0.1, "end_before_s": 0.1}}
SPEC
fail() { echo "FAIL: $*" >&2; exit 1; }

"$kuavo" campaign "$dir/spec.json" --out "$dir/a" > /dev/null 2> "$dir/a.log" || fail "first campaign"
mkdir -p "$dir/b/motions" && cp "$dir/a/motions/dance.motion" "$dir/b/motions/" || fail "copy the motion"
"$kuavo" campaign "$dir/spec.json" --out "$dir/b" > /dev/null 2> "$dir/b.log" || fail "second campaign"
cmp "$dir/a/runs.csv" "$dir/b/runs.csv" || fail "two runs of the campaign gave different tables"
cmp "$dir/a/summary.json" "$dir/b/summary.json" || fail "two runs of the campaign gave different summaries"

rows=$(tail -n +2 "$dir/a/runs.csv" | wc -l)
[ "$rows" -eq 4 ] || fail "expected 4 runs, got $rows"
# Column 8 is ok: every run simulated to its end.
bad=$(tail -n +2 "$dir/a/runs.csv" | awk -F, '$8 != 1' | wc -l)
[ "$bad" -eq 0 ] || fail "$bad runs failed: $(cat "$dir/a/runs.csv")"
grep -q '"runs": 4' "$dir/a/summary.json" || fail "summary.json lacks runs = 4"
grep -q '"fall_rate_ci95"' "$dir/a/summary.json" || fail "summary.json lacks the interval"
# The same seed with and without the perturbation set: different logs (last column: the log hash).
none=$(grep '__none__1,' "$dir/a/runs.csv" | awk -F, '{print $NF}')
show=$(grep '__show__1,' "$dir/a/runs.csv" | awk -F, '{print $NF}')
[ -n "$none" ] && [ "$none" != "$show" ] || fail "the perturbation set did not change the run"
grep -q '"perturbation"' "$dir/a/runs/dance__floor__show__1.json" || fail "the summary does not echo the perturbation"

# Resume: only the removed run is redone, and the table is unchanged.
rm "$dir/a/runs/dance__floor__show__2.json"
"$kuavo" campaign "$dir/spec.json" --out "$dir/a" > /dev/null 2> "$dir/resume.log" || fail "resumed campaign"
grep -q "4 runs, 1 to do, 3 already done" "$dir/resume.log" || fail "resume did not skip the finished runs: $(cat "$dir/resume.log")"
cmp "$dir/a/runs.csv" "$dir/b/runs.csv" || fail "the resumed campaign gave a different table"

# The offline stage twice (repair, TO; no closed-loop check): the same motion bytes.
for k in 1 2; do
  "$kuavo" retarget -o "$dir/r$k.motion" --report "$dir/r$k.json" --verify 0 --figures none --quiet \
    > /dev/null 2>&1 || fail "retarget $k"
done
cmp "$dir/r1.motion" "$dir/r2.motion" || fail "two retargets of the built-in dance gave different motions"

# --seeds overrides the spec. The built-in dance's motion is reused from the first campaign.
mkdir -p "$dir/c/motions" && cp "$dir/a/motions/dance.motion" "$dir/c/motions/" || fail "copy the motion"
"$kuavo" campaign "$dir/spec.json" --out "$dir/c" --seeds 1 > /dev/null 2>&1 || fail "--seeds 1"
[ "$(tail -n +2 "$dir/c/runs.csv" | wc -l)" -eq 2 ] || fail "--seeds 1 should give 2 runs"
echo "campaign: deterministic, resumable, $rows runs"
