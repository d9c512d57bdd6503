#!/bin/bash
# set-a fits with the given label and flags, one at a time, then from-flat drapes at 41/61/81
D=/work/main/build/bin/drape; S=/work/shared/data/drape-lab/set-a
label=$1; shift
mkdir -p $label
for r in $S/DL-A*; do id=$(basename $r)
  /usr/bin/time -f "%e" -o $label/$id.time $D fit $r --out $label/$id.json --json --quiet "$@" > $label/$id.fit.json 2> $label/$id.fit.err
done
for r in $S/DL-A*; do id=$(basename $r)
  for g in 41 61 81; do
    OMP_NUM_THREADS=1 $D simulate --fabric $label/$id.json --sample-diameter 300mm --disc-diameter 150mm --grid $g --json --quiet --max-time 600 > $label/$id.flat$g.json 2>/dev/null &
    if [ $g = 61 ]; then wait; fi
  done; wait
done
