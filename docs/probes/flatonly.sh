#!/bin/bash
D=/work/main/build/bin/drape; label=$1
for i in 01 02 03 04 05 06 07 08 09 10; do id=DL-A$i
  for g in 41 61 81; do
    [ -s $label/$id.flat$g.json ] && continue
    OMP_NUM_THREADS=1 $D simulate --fabric $label/$id.json --sample-diameter 300mm --disc-diameter 150mm --grid $g --json --quiet --max-time 600 > $label/$id.flat$g.json 2>/dev/null &
    if [ $g = 61 ]; then wait; fi
  done; wait
done
