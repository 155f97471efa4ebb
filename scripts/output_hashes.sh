#!/usr/bin/env bash
# Hash every output the CLI writes from the bundled fixtures, for refactors that must not
# change a byte (issue 30: "change no pixel").
#
#   scripts/output_hashes.sh BIN OUT.txt      # BIN: a day2night binary (a release build)
#
# Run it with the binary built before a refactor and with the one built after, then
# `diff before.txt after.txt`: any line that differs names the output (and the command
# that wrote it) whose bytes changed. OUT.txt is a sorted list of "sha256  path" lines; the
# paths are relative to a scratch folder, so two runs compare wherever they ran. stdout of
# the commands that print JSON (info, dataset, report, eval, merge) is hashed too, as
# `<name>.stdout`, without its wall-clock "seconds" lines.
#
# Covered: synth with the defaults and with --target both --variants 2 --iso 800,1600,3200,
# --compat release, --input-exr --compression ljpeg, and a burst; render to EXR, PNG (every
# tone, 8 and 16 bits, camera RGB) and TIFF; convert with the raw in a SubIFD (the DNG
# thumbnail) and with LJ92; info --json; eval --json; calibrate illuminants; merge; a small
# dataset and its report. Every fixture under fixtures/*.dng goes through synth, render,
# convert and info; the heavier commands use day.dng and one synthetic fixture.
set -euo pipefail

if [ $# -ne 2 ]; then
    echo "usage: $0 BIN OUT.txt" >&2
    exit 2
fi
bin=$(realpath "$1")
out=$(realpath -m "$2")
repo=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
mkdir in render convert calibrate merge
cp "$repo"/fixtures/*.dng in/

run() { # run NAME ARGS...: the command's stdout goes to NAME.stdout
    local name=$1
    shift
    if ! "$bin" "$@" >"$name.stdout" 2>"$name.stderr"; then
        echo "failed: $bin $*" >&2
        cat "$name.stderr" >&2
        exit 1
    fi
    rm -f "$name.stderr"
}

fixtures=$(cd in && ls *.dng)
run info info --json $(for f in $fixtures; do echo "in/$f"; done)
for f in $fixtures; do
    s=${f%.dng}
    run "synth-$s" synth "in/$f" -o "synth/default" -q
    run "render-$s-exr" render "in/$f" -o "render/$s.exr"
    run "render-$s-png" render "in/$f" -o "render/$s.png"
    run "render-$s-tif" render "in/$f" -o "render/$s.tif"
    run "convert-$s-sub" convert "in/$f" -o "convert/${s}_sub.dng" --raw-ifd sub
    run "convert-$s-ljpeg" convert "in/$f" -o "convert/${s}_ljpeg.dng" --compression ljpeg
done
big="in/day.dng in/rggb_12bit_ljpeg_tiles_deltas.dng"
run synth-both synth $big -o synth/both --target both --variants 2 --iso 800,1600,3200 -q
run synth-release synth $big -o synth/release --compat release --target both -q
run synth-exr synth $big -o synth/exr --input-exr --compression ljpeg -q
run synth-burst synth in/day.dng -o synth/burst --burst 3 --iso 3200 -q
run synth-sub synth synth/default/day_clean.dng -o synth/of_a_night -q
for tone in gamma22 release; do
    run "render-tone-$tone" render in/day.dng -o "render/day_$tone.png" --tone "$tone"
done
run render-16 render in/day.dng -o render/day_16.png --bits 16
run render-float render in/day.dng -o render/day_float.exr --float
run render-camera render in/day.dng -o render/day_camera.png --camera-rgb
run render-menon render in/day.dng -o render/day_menon.tif --demosaic menon --no-crop
run render-night render synth/default/day_iso3200.dng -o render/night.png
run eval-png eval render/night.png render/day.png --json
run eval-exr eval render/day_float.exr render/day.exr --json
run calibrate calibrate illuminants in/day.dng in/rggb_16bit_le_strips.dng -o calibrate/ill.json
run merge merge synth/burst/day_iso3200_f00.dng synth/burst/day_iso3200_f01.dng \
    synth/burst/day_iso3200_f02.dng -o merge/merged.dng --json
mkdir day
cp in/day.dng in/rggb_16bit_le_strips.dng in/grbg_12bit_packed_be_strips.dng day/
run dataset dataset day -o dataset --val 1 --jobs 1 -q --json
run report report dataset --day-dir day --samples 3 --json

# Wall-clock fields are the only run-dependent bytes: drop them before hashing.
sed -i '/"seconds":/d' ./*.stdout
find . -type f ! -path './in/*' ! -path './day/*' -print0 | sort -z | xargs -0 sha256sum \
    | sort -k2 >"$out"
echo "$(wc -l <"$out") outputs hashed into $out" >&2
