#!/bin/bash
# The seven sample songs planned, checked and replayed in full contact by one checkout,
# one line each (notes played, play's and check's frame F1, physics F1, wrong keys).
#
# usage: bench/sample_songs.sh TREE HAND OUT
#   TREE: the checkout measured (its planner and its songs/), HAND: a hand name
#   (`default`, `mk5`, `agh`; for a hand other than default its atlas is made first, in
#   TREE), OUT: a folder for the plans and each command's output.
set -u
[ $# -eq 3 ] || { echo "usage: $0 TREE HAND OUT" >&2; exit 2; }
TREE=$(cd "$1" && pwd) || exit 2
H=$2
mkdir -p "$3" && O=$(cd "$3" && pwd) || exit 2
cd "$TREE" && export PYTHONPATH="$TREE"
[ "$H" != default ] && python scripts/make_atlas.py --hand "$H" 2>&1 | grep -v Warn | tail -2
for s in chords fast fur_elise leaps ode_to_joy scale twinkle; do
  python cli.py play "songs/$s.mid" --hand "$H" -o "$O/$s.csv" > "$O/$s.play" 2>&1
  f1=$(grep -o "frame F1 [0-9.]*" "$O/$s.play" | tail -1)
  pl=$(grep -o "[0-9]* notes, [0-9]* played" "$O/$s.play" | head -1)
  python cli.py check "$O/$s.csv" "songs/$s.mid" --hand "$H" > "$O/$s.check" 2>&1
  bf=$(grep -o "frame F1 [0-9.]*" "$O/$s.check")
  python cli.py simulate "$O/$s.csv" "songs/$s.mid" --hand "$H" > "$O/$s.sim" 2>&1
  ph=$(grep -o "physics frame F1 [0-9.]*" "$O/$s.sim")
  wk=$(grep -o "[0-9]* wrong keys" "$O/$s.sim")
  echo "$s | $pl | play $f1 | check $bf | $ph | $wk"
done
