#!/bin/sh
# MPI benchmark of `btr relax` (LIGGGHTS): the same packing relaxed with --np 1 and --np 2, alternating,
# REPS times each; prints every run's engine wall time and the ratio t(np 1) / t(np 2) of each pair
# (above 1: two ranks are faster). Run it on an idle machine if you can: two ranks need two free cores.
#   scripts/bench_relax_np.sh PACKING.csv [MAX_TIME=0.02] [REPS=3] [BTR=build/app/btr]
# e.g.  build/app/btr deposit inputs/bed3d.toml --count 30000 -o /tmp/bed30k -q
#       scripts/bench_relax_np.sh /tmp/bed30k/bed3d.csv 0.02 3
set -eu
packing=$1
max_time=${2:-0.02}
reps=${3:-3}
btr=${4:-build/app/btr}
out=$(mktemp -d)
wall() { sed -n 's/.*"wall_seconds": *\([0-9.eE+-]*\).*/\1/p' "$1/relaxed.json" | head -1; }
# Stepping time alone: the sum of LIGGGHTS' "Loop time" lines over the steps run, in ms per step.
per_step() { awk '/^Loop time of/ {t += $4; n += $9} END {printf "%.3f", 1000 * t / n}' "$1/log.liggghts"; }
echo "packing $packing, max_time $max_time s, $reps pairs, load average: $(cut -d' ' -f1-3 /proc/loadavg)"
i=1
while [ "$i" -le "$reps" ]; do
  for np in 1 2; do
    "$btr" relax "$packing" -o "$out/np$np" --max-time "$max_time" --np "$np" > "$out/np$np.txt"
  done
  t1=$(wall "$out/np1")
  t2=$(wall "$out/np2")
  s1=$(per_step "$out/np1")
  s2=$(per_step "$out/np2")
  echo "pair $i: np1 $t1 s ($s1 ms/step), np2 $t2 s ($s2 ms/step), ratio np1/np2 $(echo "scale=3; $t1 / $t2" | bc)," \
       "per step $(echo "scale=3; $s1 / $s2" | bc)"
  i=$((i + 1))
done
grep "stopped by" "$out/np1.txt" "$out/np2.txt" | sed "s|$out/||"
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
rm -rf "$out"
