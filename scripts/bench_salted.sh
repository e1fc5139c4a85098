#!/bin/sh
# btr against SALTED (Topic and Poeschel 2016, github.com/vsangelidakis/SALTED), side by side on SALTED's own
# sphere bed: 20000 equal spheres of radius 30 in a periodic 3000 x 3000 cell (its src/input), btr's scene
# the same bed in SI (radius 3 mm, cell 0.3 m). SALTED is not part of btr-dem: bring its source yourself.
# Builds SALTED twice, as its makefile does (GSL paths unset, so "-I -O3" swallows -O3: no optimisation) and
# with -O3 restored (libgsl-dev needed), then runs btr and both builds alternately REPS times. Prints each
# run's processor time (btr's the mean of ten runs), the mean centre heights (the same bed: they agree to 0.1 %) and the ratios.
#   scripts/bench_salted.sh SALTED_CHECKOUT [REPS=3] [BTR=build/app/btr]
set -eu
salted=$1
reps=${2:-3}
btr=$(realpath "${3:-build/app/btr}")
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for build in asis O3; do
  cp -r "$salted/src" "$out/$build"
  rm -f "$out/$build"/*.o "$out/$build/deposit"  # built here, from source
done
make -s -C "$out/asis" > /dev/null
make -s -C "$out/O3" GSL_INCLUDE_PATH=/usr/include GSL_LIBRARY_PATH=/usr/lib/x86_64-linux-gnu > /dev/null
cat > "$out/salted_bed.toml" <<'EOF'
[scene]
name = "salted_bed"
dimension = 3
seed = 1
[grains]
count = 20000
density = 2500.0
radius = { distribution = "constant", value = 3.0e-3 }
[container]
kind = "periodic"
size = [0.3, 0.3]
[source]
kind = "rain"
[material]
young = 5e6
poisson = 0.3
restitution = 0.5
friction = 0.5
EOF
cpu() { awk -v n="${2:-1}" '{printf "%.3f", ($1 + $2) / n}' "$1"; }
ratio() { awk -v a="$1" -v b="$2" 'BEGIN {printf "%.0f", a / b}'; }
echo "btr against SALTED, 20000 spheres, $reps rounds, load average: $(cut -d' ' -f1-3 /proc/loadavg)"
i=1
while [ "$i" -le "$reps" ]; do
  # btr ten times in one timing: one run is about 0.1 s, /usr/bin/time's resolution 0.01 s
  /usr/bin/time -f "%U %S" -o "$out/btr.t" sh -c 'for k in 1 2 3 4 5 6 7 8 9 10; do
    "$0" deposit "$1" -o "$2" -q; done' "$btr" "$out/salted_bed.toml" "$out/btr"
  for build in asis O3; do
    # arguments: rotation step 0.01 rad, seed 1, 1 sphere a particle, spheres, 20000 particles, redrop, tag
    (cd "$out/$build" && /usr/bin/time -f "%U %S" -o run.t ./deposit 0.01 1 1 0 20000 1 run > run.log)
  done
  b=$(cpu "$out/btr.t" 10)
  a=$(cpu "$out/asis/run.t")
  o=$(cpu "$out/O3/run.t")
  echo "round $i: btr $b s, SALTED as built by its makefile $a s ($(ratio "$a" "$b")x)," \
       "SALTED -O3 $o s ($(ratio "$o" "$b")x)"
  i=$((i + 1))
done
btr_z=$(sed -n 's/.*"mean_centre": *\([0-9.eE+-]*\).*/\1/p' "$out/btr/salted_bed.json" | head -1)
salted_z=$(awk '{z += $3} END {printf "%.6f", 1e-4 * z / NR}' "$out/O3/positions/positionsrun")
echo "mean centre height: btr $btr_z m, SALTED $salted_z m (its units x 1e-4)"
