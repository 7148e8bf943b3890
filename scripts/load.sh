#!/usr/bin/env bash
# One end-to-end load measurement of `mpmwatch serve` on loopback: starts the monitor (release
# binary) with N synthetic 3x3 controllers, runs `mpmwatch loadgen` against it, samples the
# monitor's CPU time and resident memory from /proc every SAMPLE seconds, waits until every
# sent sample is accounted for, and prints sent / ingested / dropped-by-reason, achieved
# samples/s, CPU and RSS, and the scheduler's figures. Not used by the tests.
#
# usage: scripts/load.sh CONTROLLERS RATE BATCH DURATION [EXTRA_TOML]
#   CONTROLLERS  synthetic 3x3 controllers (ids lg000..)
#   RATE         rows per second per controller (loadgen --rate; 0 = as fast as possible)
#   BATCH        samples per message (1 = single-sample payloads)
#   DURATION     seconds of publishing
#   EXTRA_TOML   lines added to every [[controller]] table
#                (default: window = 2048, lag_max = 20, surrogates = 100, every = 60)
# environment: BIN (default target/release/mpmwatch), ZPORT, HPORT, SAMPLE (s, default 10),
#   QUEUE_MESSAGES, QUEUE_BYTES (the [ingest] section), OUT (directory for the raw files),
#   SETTLE (seconds to keep the monitor running after the generator stops, default 5),
#   MONITOR_WRAP / GEN_WRAP (commands put before the monitor / the generator, e.g.
#   "taskset -c 1 nice -n 11" and "taskset -c 1": both on one core, the monitor at a lower
#   priority, to offer it many times what it can take on a 2-core machine).
set -euo pipefail

N=${1:?controllers}; RATE=${2:?rate}; BATCH=${3:?batch}; DUR=${4:?duration}
EXTRA=${5:-$'window = 2048\nmin_samples = 2048\nlag_max = 20\nsurrogates = 100\nevery = 60'}
BIN=${BIN:-target/release/mpmwatch}
ZPORT=${ZPORT:-17501}; HPORT=${HPORT:-19501}; SAMPLE=${SAMPLE:-10}; SETTLE=${SETTLE:-5}
OUT=${OUT:-$(mktemp -d /tmp/mpmwatch-load.XXXXXX)}
mkdir -p "$OUT"
TCK=$(getconf CLK_TCK)

{
  printf '[zenoh]\nmode = "peer"\nlisten = ["tcp/127.0.0.1:%s"]\n' "$ZPORT"
  printf '[http]\nbind = "127.0.0.1:%s"\n' "$HPORT"
  printf '[ingest]\nqueue_messages = %s\nqueue_bytes = %s\n\n' "${QUEUE_MESSAGES:-256}" "${QUEUE_BYTES:-2097152}"
  "$BIN" loadgen --controllers "$N" --batch "$BATCH" --print-config --extra "$EXTRA"
} > "$OUT/serve.toml"

RUST_LOG=${RUST_LOG:-warn} ${MONITOR_WRAP:-} "$BIN" serve --config "$OUT/serve.toml" 2> "$OUT/serve.log" &
SERVE=$!
trap 'kill $SERVE 2>/dev/null || true; kill $SAMPLER 2>/dev/null || true' EXIT
for _ in $(seq 100); do curl -sf "http://127.0.0.1:$HPORT/healthz" > /dev/null && break; sleep 0.2; done

cpu_ticks() { awk '{print $14 + $15}' "/proc/$SERVE/stat"; }
rss_kib() { awk '/^VmRSS:/ {print $2}' "/proc/$SERVE/status"; }

# time since start (s), service CPU ticks, RSS KiB, load average
START=$(date +%s.%N)
( while kill -0 $SERVE 2>/dev/null; do
    echo "$(echo "$(date +%s.%N) - $START" | bc) $(cpu_ticks) $(rss_kib) $(cut -d' ' -f1 /proc/loadavg)"
    sleep "$SAMPLE"
  done ) > "$OUT/samples.txt" &
SAMPLER=$!

T0=$(cpu_ticks); W0=$(date +%s.%N)
${GEN_WRAP:-} "$BIN" loadgen --connect "tcp/127.0.0.1:$ZPORT" --controllers "$N" --rate "$RATE" --batch "$BATCH" \
  --duration "$DUR" --wait 60 --json > "$OUT/loadgen.json"
T1=$(cpu_ticks); W1=$(date +%s.%N)
SENT=$(jq .samples "$OUT/loadgen.json")

# Wait for the queues to drain: every sent sample ingested or dropped with a reason.
acc() {
  curl -s "http://127.0.0.1:$HPORT/metrics" > "$OUT/metrics.txt"
  awk -v b="$BATCH" '
    /^mpm_samples_ingested_total/ {i += $NF}
    /^mpm_samples_dropped_total/ { if ($0 ~ /queue_full/) q += $NF; else d += $NF }
    END {printf "%.0f %.0f %.0f %.0f\n", i, d, q, i + d + q * b}' "$OUT/metrics.txt"
}
for _ in $(seq 600); do
  read -r ING DROP QF TOTAL < <(acc)
  [ "$TOTAL" -ge "$SENT" ] && break
  sleep 0.5
done
sleep "$SETTLE"
read -r ING DROP QF TOTAL < <(acc)

echo "== $N controllers x 12 tags, rate $RATE rows/s per controller, batch $BATCH, $DUR s (raw files: $OUT)"
jq -r '"loadgen: sent \(.samples) samples in \(.messages) messages over \(.elapsed_s|.*10|round/10) s = \(.samples_per_s|round) samples/s (target \(.samples_per_s_target|round)); put errors \(.put_errors); keys without subscriber \(.unmatched_keys)"' "$OUT/loadgen.json"
echo "monitor: ingested $ING, dropped (other reasons) $DROP, queue_full $QF messages = $((QF * BATCH)) samples; unaccounted $((SENT - TOTAL))"
grep '^mpm_samples_dropped_total' "$OUT/metrics.txt" | awk '$NF > 0' | sed 's/controller="[^"]*",//' \
  | awk '{split($1, a, "reason=\""); split(a[2], r, "\""); s[r[1]] += $NF} END {for (k in s) printf "  dropped %s: %d\n", k, s[k]}'
echo "monitor CPU during publishing: $(echo "scale=1; 100 * ($T1 - $T0) / $TCK / ($W1 - $W0)" | bc) % of one core (over $(echo "$W1 - $W0" | bc | cut -c1-6) s)"
echo "monitor RSS KiB: $(awk '{print $3}' "$OUT/samples.txt" | sort -n | head -1) min, $(awk '{print $3}' "$OUT/samples.txt" | sort -n | tail -1) max, $(tail -1 "$OUT/samples.txt" | awk '{print $3}') last ($(wc -l < "$OUT/samples.txt") samples every ${SAMPLE} s)"
echo "load average (1 min) during the run: $(awk '{print $4}' "$OUT/samples.txt" | sort -n | head -1) .. $(awk '{print $4}' "$OUT/samples.txt" | sort -n | tail -1)"
awk '
  /^mpm_runs_total/ {split($0, a, "status=\""); split(a[2], s, "\""); runs[s[1]] += $NF}
  /^mpm_runs_late_total/ {late += $NF}
  /^mpm_runs_missed_total/ {missed += $NF}
  /^mpm_last_run_duration_seconds/ {n++; d += $NF; if ($NF > dmax) dmax = $NF}
  /^mpm_run_lateness_seconds/ {if ($NF > lmax) lmax = $NF}
  /^mpm_active_alarms/ {alarms += $NF}
  END {
    printf "scheduler: runs"; for (k in runs) printf " %s=%d", k, runs[k];
    printf "; late %d, missed %d; last run duration mean %.2f s, max %.2f s; max start lateness %.3f s; active alarms %d\n",
      late, missed, (n ? d / n : 0), dmax, lmax, alarms
  }' "$OUT/metrics.txt"
