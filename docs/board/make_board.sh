#!/bin/sh
# Renders the picture board of docs/BOARD.md into docs/board/: the convective genera, the
# cloudscape and the presets built from ellipsoids or automata, each from three places, with
# the sun in front of the camera (its azimuth the camera's heading) and behind it (opposite),
# 25 degrees up. 320x180 PNG, about 3 MB in all.
#
# The sea's board (issue 48): sea states 1, 3, 5 and 7, each from 300 m and 3 km, sun 60 and
# 12 degrees up, with and without clouds, from bench/sea_bench --board, set side by side with
# oiiotool.
#
#   docs/board/make_board.sh [path/to/nephele] [path/to/sea_bench]
#                                      (default build/nephele, build/bench/sea_bench)
set -eu
nephele=${1:-build/nephele}
sea_bench=${2:-build/bench/sea_bench}
here=$(cd "$(dirname "$0")" && pwd)
scenes="$here/../../config/scenes"

# shot PRESET VIEW HEADING [camera flags...]: the view twice, sun in front and sun behind.
shot() {
  preset=$1 view=$2 heading=$3
  shift 3
  for sun in front behind; do
    if [ "$sun" = front ]; then azimuth=$heading; else azimuth=$(( (heading + 180) % 360 )); fi
    "$nephele" render "$scenes/$preset.toml" -o "$here/${preset}_${view}_sun_$sun.png" \
      --width 320 --height 180 --heading "$heading" --sun "$azimuth,25" "$@" >/dev/null 2>&1 ||
      { echo "failed: $preset $view, sun $sun" >&2; exit 1; }
    echo "  $preset $view, sun $sun"
  done
}

# Weather presets: from the ground; from just under the heaps' base, level, with a 30 degree
# lens (heaps 10 km off stand a tenth of the view high); from 1.5 km above their top.
shot genus_cumulus ground 40 --position 0,0,2 --pitch 15 --vfov 60
shot genus_cumulus side 40 --position 0,0,1000 --pitch 2 --vfov 30
shot genus_cumulus above 40 --position 0,0,4200 --pitch -20 --vfov 60
# The species of cumulus (a thinner and a thicker layer than genus_cumulus), from the side.
shot cumulus_humilis side 40 --position 0,0,1800 --pitch -3 --vfov 30
shot cumulus_congestus side 40 --position 0,0,1000 --pitch 8 --vfov 30
shot genus_cumulonimbus ground 40 --position 0,0,2 --pitch 15 --vfov 60
shot genus_cumulonimbus side 40 --position 0,-10000,700 --pitch 12 --vfov 60
shot genus_cumulonimbus above 40 --position 0,0,12900 --pitch -20 --vfov 60
# The storm (issue 47): the raining cumulonimbus of storm.toml, the storm at (-8173, -8141),
# from the ground 5 and 20 km south of it, from the side at 30 km and 3 km up, and from 15 km
# up 18 km south; the cumulus field's shadows from 6 km straight-ish down; rain.toml's view.
shot storm ground5 0 --position -8173,-13141,2 --pitch 28 --vfov 70
shot storm ground20 0 --position -8173,-28141,2 --pitch 14 --vfov 40
shot storm side30 0 --position -8173,-38141,3000 --pitch 6 --vfov 40
shot storm above 0 --position -8173,-26000,15000 --pitch -30 --vfov 60
shot genus_cumulus shadows 40 --position 0,0,6000 --pitch -50 --vfov 60
shot rain own 0
shot cloudscape ground 200 --position 0,0,2 --pitch 12 --vfov 60
shot cloudscape side 200 --position 0,0,900 --pitch 2 --vfov 30
shot cloudscape above 200 --position 0,0,4300 --pitch -20 --vfov 60
# Scene presets: their own view, and from 3 km above it looking down at 30 degrees.
shot cumulus own 0 --position 0,-4500,300 --pitch 10 --vfov 40
shot cumulus above 0 --position 0,-6000,4500 --pitch -30 --vfov 40
shot cumulus_target own 0 --position -250,-3200,1080 --pitch -1.2 --vfov 4
shot gardner_cluster own 0 --position 0,-7000,600 --pitch 10 --vfov 50
shot gardner_cluster above 0 --position 0,-9000,5000 --pitch -30 --vfov 50
shot harbour own 0 --position 0,-3000,150 --pitch 8 --vfov 55
shot harbour above 0 --position 0,-3500,2500 --pitch -30 --vfov 55
# The search at sea, its own view and from 1.5 km, sun in front and behind.
shot sea_search own 0
shot sea_search above 0 --position 0,-2000,1500 --pitch -35

# The sea's states: one picture a state, 300 m above and 3 km below, sun 60 then 12 degrees
# up, each without and with clouds.
tmp=$(mktemp -d)
"$sea_bench" --repeats 1 --board "$tmp" >/dev/null
for state in 1 3 5 7; do
  set --
  for altitude in 0300m 3000m; do
    for sun in sun60 sun12; do
      set -- "$@" "$tmp/ss${state}_${altitude}_${sun}_clear.png" "$tmp/ss${state}_${altitude}_${sun}_clouds.png"
    done
  done
  oiiotool "$@" --mosaic 4x2 --resize 1280x360 -o "$here/sea_state_$state.png"
  echo "  sea state $state"
done
rm -r "$tmp"
