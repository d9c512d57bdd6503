#!/bin/bash
# extra seeds 2,3 at grids 41 and 61 for every label's presets (two drapes at a time)
cd /work/exp/s19; D=/work/main/build/bin/drape
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
for L in "$@"; do for i in 01 02 03 04 05 06 07 08 09 10; do id=DL-A$i
  for s in 2 3; do
    for g in 41 61; do
      $D simulate --fabric p$L/$id.json --sample-diameter 300mm --disc-diameter 150mm --grid $g --seed $s --json --quiet --max-time 600 > p$L/$id.flat$g.s$s.json 2>/dev/null &
    done; wait
  done
done; echo "seeds done $L $(date)"; done
