#!/bin/sh
# A small campaign (1 motion × 1 ground × 2 perturbation sets × 2 seeds, 0.6 s runs with a
# random push) run twice: the two tables are the same file, every run finished, the
# perturbed runs differ from the unperturbed ones, and a resumed campaign redoes only the
# run that was removed and gives the same table again. The offline stage's own determinism is
# checked first, by retargeting the built-in dance twice without the closed-loop check; the
# campaigns then run on that motion, put where a campaign keeps the built-in dance it makes
# (DIR/motions/dance.motion: a campaign reuses it). Making it in the campaign (`kuavo retarget`
# with its check, ~4 min in CI) is what mocap_cli.DynamicStageReportAndCsv runs already; here
# the campaign's call of it is checked to fail loudly. Then --attribute on a run toppled by a push.
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

# The offline stage twice (repair, TO; no closed-loop check): the same motion bytes.
for k in 1 2; do
  "$kuavo" retarget -o "$dir/r$k.motion" --report "$dir/r$k.json" --verify 0 --figures none --quiet \
    > /dev/null 2>&1 || fail "retarget $k"
done
cmp "$dir/r1.motion" "$dir/r2.motion" || fail "two retargets of the built-in dance gave different motions"

# The campaign makes the built-in dance with `kuavo retarget` when it has none: a failure there
# (its output path a directory) stops the campaign with the reason, before any run.
mkdir -p "$dir/f/motions/dance.motion.part"
if "$kuavo" campaign "$dir/spec.json" --out "$dir/f" > /dev/null 2> "$dir/f.log"; then fail "a failed retarget ran on"; fi
grep -q "retargeting the built-in dance failed" "$dir/f.log" || fail "no reason for the failed retarget: $(cat "$dir/f.log")"
[ ! -e "$dir/f/runs.csv" ] || fail "runs after a failed retarget"

mkdir -p "$dir/a/motions" && cp "$dir/r1.motion" "$dir/a/motions/dance.motion" || fail "place the motion"
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

# The surface sink is per ground: the carpet's runs get --surface-sink and echo it, the floor's not.
cat > "$dir/sink.json" <<'SPEC'
{"name": "sink", "motions": ["dance"], "grounds": ["floor", "carpet"], "perturbations": ["none"], "seeds": 1,
 "duration_s": 0.3, "surface_sink_m": {"carpet": 0.015}}
SPEC
mkdir -p "$dir/s/motions" && cp "$dir/a/motions/dance.motion" "$dir/s/motions/" || fail "copy the motion"
"$kuavo" campaign "$dir/sink.json" --out "$dir/s" > /dev/null 2>&1 || fail "campaign with a surface sink"
grep -q -- "--ground carpet .*--surface-sink 0.015" "$dir/s/jobs.txt" || fail "the carpet run lacks its sink: $(cat "$dir/s/jobs.txt")"
! grep -q -- "--ground floor .*--surface-sink" "$dir/s/jobs.txt" || fail "the floor run got the carpet's sink"
grep -q '"surface_sink_m": 0.0150' "$dir/s/runs/dance__carpet__none__1.json" || fail "the carpet run does not echo its sink"
! grep -q surface_sink "$dir/s/runs/dance__floor__none__1.json" || fail "the floor run echoes a sink"

# --seeds overrides the spec. The built-in dance's motion is reused again.
mkdir -p "$dir/c/motions" && cp "$dir/a/motions/dance.motion" "$dir/c/motions/" || fail "copy the motion"
"$kuavo" campaign "$dir/spec.json" --out "$dir/c" --seeds 1 > /dev/null 2>&1 || fail "--seeds 1"
[ "$(tail -n +2 "$dir/c/runs.csv" | wc -l)" -eq 2 ] || fail "--seeds 1 should give 2 runs"
# --attribute: an 80 N·s push (1.5 m/s on 55 kg) topples the standing robot with and without
# the show set's model errors. Only the run with errors is attributed (the one without has
# nothing to split): it is run again with the push alone on the nominal plant (it falls) and
# with the errors alone (it stands), each the same log as `kuavo simulate` of that half:
# cause "push". A third run repeats it with the true base state (--state truth, the same log as
# `kuavo simulate --state truth`): it falls too, so the estimate is not counted as having a
# part. A fourth repeats it with noise-free sensors (--sensors ideal, the same log as `kuavo
# simulate --sensors ideal`, not the fall's own): it falls too, so sensor_noise is 0. The
# campaign's own table does not change; a campaign without --attribute has no "fall_causes";
# a resumed one redoes nothing and says the same.
grep -q -- " --planner mpc --ground floor --perturb 'show' --seed 1 --perturb-seed 1 --duration 0.6 --push " \
  "$dir/b/jobs.txt" || fail "a run's command changed: $(cat "$dir/b/jobs.txt")"
cat > "$dir/attr.json" <<'SPEC'
{"name": "attr", "motions": ["dance"], "grounds": ["floor"], "perturbations": ["none", "show"], "seeds": 1,
 "duration_s": 1.5, "push": {"impulse_Ns": 80.0, "duration_s": 0.1, "start_after_s": 0.2, "end_before_s": 1.0}}
SPEC
mkdir -p "$dir/t/motions" && cp "$dir/a/motions/dance.motion" "$dir/t/motions/" || fail "copy the motion"
"$kuavo" campaign "$dir/attr.json" --out "$dir/t" > /dev/null 2>&1 || fail "campaign before --attribute"
grep -q '"falls": 2' "$dir/t/summary.json" || fail "the 80 N·s push did not topple the robot: $(cat "$dir/t/runs.csv")"
! grep -q fall_causes "$dir/t/summary.json" || fail "fall_causes without --attribute"
push=$(grep -o -- "--push [^ ]*" "$dir/t/jobs.txt" | head -n 1) || fail "no push in $dir/t/jobs.txt"
cp "$dir/t/runs.csv" "$dir/runs_before.csv"
"$kuavo" campaign "$dir/attr.json" --out "$dir/t" --attribute > /dev/null 2> "$dir/attr.log" || fail "--attribute"
grep -q "attribution of 1 falls, 4 runs to do" "$dir/attr.log" || fail "attribution runs: $(cat "$dir/attr.log")"
cmp "$dir/runs_before.csv" "$dir/t/runs.csv" || fail "--attribute changed runs.csv"
[ "$(head -n 1 "$dir/t/attribution.csv")" = "run,motion,cause,push_alone_fell_at_s,errors_alone_fell_at_s,true_state_fell_at_s,state_estimate,ideal_sensors_fell_at_s,sensor_noise" ] ||
  fail "attribution.csv header: $(head -n 1 "$dir/t/attribution.csv")"
[ "$(tail -n +2 "$dir/t/attribution.csv" | wc -l)" -eq 1 ] || fail "expected one attributed fall: $(cat "$dir/t/attribution.csv")"
row=$(tail -n +2 "$dir/t/attribution.csv")
[ "$(echo "$row" | cut -d, -f1-3)" = "dance__floor__show__1,dance,push" ] || fail "attribution: $row, expected cause push"
grep -q '"push": 1' "$dir/t/summary.json" || fail "summary.json fall_causes: $(cat "$dir/t/summary.json")"
grep -q '"state_estimate": 0' "$dir/t/summary.json" || fail "summary.json state_estimate: $(cat "$dir/t/summary.json")"
grep -q '"sensor_noise": 0' "$dir/t/summary.json" || fail "summary.json sensor_noise: $(cat "$dir/t/summary.json")"
# Each half is `kuavo simulate` of that half in its own process: the same log, bit for bit.
"$kuavo" simulate "$dir/t/motions/dance.motion" --planner mpc --ground floor --seed 1 --duration 1.5 $push \
  --summary "$dir/push_alone.json" > /dev/null 2>&1 || fail "simulate the push alone"
"$kuavo" simulate "$dir/t/motions/dance.motion" --planner mpc --ground floor --seed 1 --duration 1.5 \
  --perturb show --perturb-seed 1 --summary "$dir/errors_alone.json" > /dev/null 2>&1 || fail "simulate the errors alone"
"$kuavo" simulate "$dir/t/motions/dance.motion" --planner mpc --ground floor --seed 1 --duration 1.5 \
  --perturb show --perturb-seed 1 $push --state truth --summary "$dir/true_state.json" > /dev/null 2>&1 ||
  fail "simulate with the true state"
"$kuavo" simulate "$dir/t/motions/dance.motion" --planner mpc --ground floor --seed 1 --duration 1.5 \
  --perturb show --perturb-seed 1 $push --sensors ideal --summary "$dir/ideal_sensors.json" > /dev/null 2>&1 ||
  fail "simulate with ideal sensors"
fell_log=$(grep '"log_sha256"' "$dir/t/runs/dance__floor__show__1.json" || true)
[ -n "$fell_log" ] && [ "$fell_log" != "$(grep '"log_sha256"' "$dir/ideal_sensors.json")" ] ||
  fail "the noise-free sensors' run is the fall's own log ($fell_log)"
for half in push_alone errors_alone true_state ideal_sensors; do
  want=$(grep '"log_sha256"' "$dir/$half.json" || true)
  got=$(grep '"log_sha256"' "$dir/t/attribution/dance__floor__show__1__$half.json" 2> /dev/null || true)
  [ -n "$want" ] && [ "$want" = "$got" ] || fail "$half: the campaign's run is not kuavo simulate's ($got, $want)"
done
grep -q '"fell": true' "$dir/push_alone.json" || fail "the push alone did not topple the nominal robot"
grep -q '"fell": false' "$dir/errors_alone.json" || fail "the model errors alone toppled a standing robot"
grep -q '"fell": true' "$dir/true_state.json" || fail "the 80 N·s push did not topple the robot with the true state"
grep -q '"fell": true' "$dir/ideal_sensors.json" || fail "the 80 N·s push did not topple the robot on ideal sensors"
alone=$(grep '"fell_at_s"' "$dir/push_alone.json" | tr -dc '0-9.-')
truth=$(grep '"fell_at_s"' "$dir/true_state.json" | tr -dc '0-9.-')
ideal=$(grep '"fell_at_s"' "$dir/ideal_sensors.json" | tr -dc '0-9.-')
[ "$(echo "$row" | cut -d, -f4-9)" = "$(printf %.3f "$alone"),-1.000,$(printf %.3f "$truth"),0,$(printf %.3f "$ideal"),0" ] ||
  fail "the runs' fall times: $row (push alone $alone, true state $truth, ideal sensors $ideal)"
"$kuavo" campaign "$dir/attr.json" --out "$dir/t" --attribute > /dev/null 2> "$dir/attr2.log" || fail "--attribute resumed"
grep -q "attribution of 1 falls, 0 runs to do" "$dir/attr2.log" || fail "resumed attribution: $(cat "$dir/attr2.log")"
[ "$(tail -n +2 "$dir/t/attribution.csv")" = "$row" ] || fail "resumed attribution: $(cat "$dir/t/attribution.csv")"

echo "campaign: deterministic, resumable, $rows runs; a pushed fall attributed to its push"
