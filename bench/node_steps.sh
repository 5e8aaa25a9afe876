#!/usr/bin/env bash
# Node-steps per second of the default scene at 260 m/s to perforation, for each contact
# model (sliding, pin_jointed), precision (double, float) and 1 and 2 solver threads.
# Writes bench/node_steps.csv (docs/tradeoff.md "Benchmark").
#
#   bench/node_steps.sh [BUILD_DIR] [REPEATS]      (defaults: build, 3)
#
# Each case runs build/bench/bench_impact under bash's `time`, so every row has the wall
# time and the process's user + system CPU time. The machine's 1-minute load average is
# read before each run and written into the row: on a shared machine the wall times (and
# the 2-thread speed-up) depend on it. Repeats are interleaved (all cases once, then again)
# so load changes spread over every case.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
build="${1:-$here/../build}"
repeats="${2:-3}"
bench="$build/bench/bench_impact"
out="$here/node_steps.csv"
[ -x "$bench" ] || { echo "node_steps.sh: $bench not found (build first)" >&2; exit 1; }

# How the solver threads wait at barriers is chosen by bench_impact at start-up from the
# machine's load, as the ravel executable does (app/cli/omp_env.h): spin up to 20,000 rounds
# when there is a core for each thread, sleep otherwise. The choice is in each row
# (omp_spincount). Set OMP_WAIT_POLICY / GOMP_SPINCOUNT to force one.

tmp="$(mktemp)"
trap 'rm -f "$tmp" "$tmp.t"' EXIT
{
  echo "# ravel node-steps per second: default scene (twaron_ct716) at 260 m/s to perforation"
  echo "# date $(date -u +%Y-%m-%dT%H:%MZ), host $(hostname), $(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')), load average at start: $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "# OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-chosen by bench_impact} GOMP_SPINCOUNT=${GOMP_SPINCOUNT:-chosen by bench_impact}"
  echo "# wall_s: elapsed; user_s/sys_s: CPU time of the process (all threads); load1: 1-minute load average just before the run"
  echo "model,precision,threads,repeat,nodes,steps,wall_s,user_s,sys_s,node_steps_per_s,node_steps_per_cpu_s,perforated,residual_velocity_mps,load1,omp_spincount,simd"
} > "$tmp"
for r in $(seq 1 "$repeats"); do
  for model in sliding pin_jointed; do
    for prec in double float; do
      for th in 1 2; do
        load="$(cut -d' ' -f1 /proc/loadavg)"
        TIMEFORMAT='%R %U %S'
        { time "$bench" --set solver.model=$model --set solver.precision=$prec --set solver.threads=$th > "$tmp.t"; } 2> "$tmp.time"
        read -r real user sys < "$tmp.time"
        # bench_impact: model,contact,precision,threads,nodes,steps,sim_time_us,wall_s,node_steps_per_s,ns_per_node_step,perforated,residual_velocity_mps,omp_spincount,simd
        line="$(tail -n1 "$tmp.t")"
        IFS=, read -r _m contact _p _t nodes steps _sim wall nsps _ns perf vr spin simd <<< "$line"
        cpu="$(awk -v u="$user" -v s="$sys" 'BEGIN{print u+s}')"
        per_cpu="$(awk -v n="$nodes" -v k="$steps" -v c="$cpu" 'BEGIN{printf "%.4g", n*k/c}')"
        echo "$contact,$prec,$th,$r,$nodes,$steps,$wall,$user,$sys,$nsps,$per_cpu,$perf,$vr,$load,$spin,$simd" >> "$tmp"
        echo "  $contact $prec threads=$th repeat $r: wall $wall s, cpu $cpu s, $nsps node-steps/s (load $load, spin $spin)" >&2
      done
    done
  done
done
rm -f "$tmp.time"
echo "# load average at end: $(cut -d' ' -f1-3 /proc/loadavg)" >> "$tmp"
mv "$tmp" "$out"
trap - EXIT
echo "wrote $out" >&2
# Speed-up of 2 threads over 1 (best wall time of the repeats; and the CPU time ratio).
# Also the median over the repeats of the paired ratio (the 1- and 2-thread runs of one
# repeat follow each other, so a drift of the machine's speed between repeats cancels; on
# a shared machine single runs spread by 10-30 % and the best of each column may come from
# different moments).
awk -F, '!/^#/ && $1 != "model" {
  k = $1 "," $2; w = $7 + 0; c = $8 + $9;
  if (!(k SUBSEP $3 in best) || w < best[k SUBSEP $3]) { best[k SUBSEP $3] = w; cpu[k SUBSEP $3] = c }
  wall[k SUBSEP $3 SUBSEP $4] = w; keys[k] = 1; if ($4 + 0 > nrep) nrep = $4 + 0 }
  END { for (k in keys) {
          n = 0
          for (r = 1; r <= nrep; ++r)
            if ((k SUBSEP 1 SUBSEP r) in wall && (k SUBSEP 2 SUBSEP r) in wall) q[++n] = wall[k SUBSEP 1 SUBSEP r] / wall[k SUBSEP 2 SUBSEP r]
          for (i = 2; i <= n; ++i) for (j = i; j > 1 && q[j - 1] > q[j]; --j) { t = q[j]; q[j] = q[j - 1]; q[j - 1] = t }
          med = n % 2 ? q[(n + 1) / 2] : (q[n / 2] + q[n / 2 + 1]) / 2
          printf "  %-20s 1 thread %.2f s, 2 threads %.2f s: speed-up %.2fx (best wall), %.2fx (median of %d paired repeats); CPU time 2 vs 1 thread %.2fx\n",
            k, best[k SUBSEP 1], best[k SUBSEP 2], best[k SUBSEP 1] / best[k SUBSEP 2], med, n, cpu[k SUBSEP 2] / cpu[k SUBSEP 1] } }' "$out" >&2
