#!/usr/bin/env bash
# The ISO 6336-1 comparison against the bore radii (issue 12, item 6). The Kurokawa papers do not
# give the bores; the example specs assume 20 / 25 mm. This reruns `fmu-build ste` (defaults:
# PMOR-Hertz, the spec's mesh, 41 positions) on copies of the spec with other bores and prints one
# markdown row per bore pair and torque: mean and peak-to-peak STE, k / c_γα, and for the spur pair
# the zone figures (single-zone stiffness / c′, double/single, zone contrast / ISO's).
# Usage: scripts/iso_bore_sensitivity.sh [spur|helical|all]   (release build of fmu-build first;
#        FMU_BUILD=/path/to/fmu-build to use another binary)
set -euo pipefail
cd "$(dirname "$0")/.."
B=${FMU_BUILD:-./target/release/fmu-build}
which=${1:-spur}
BORES=${BORES:-"20/25 30/45 40/70"}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# with_bores <spec> <gear1 mm> <gear2 mm> <out>: the spec with bore_radius_mm replaced per section.
with_bores() {
    awk -v r1="$2" -v r2="$3" '
        /^\[/ { section = $0 }
        /^bore_radius_mm/ && section == "[gear1]" { $0 = "bore_radius_mm = " r1 }
        /^bore_radius_mm/ && section == "[gear2]" { $0 = "bore_radius_mm = " r2 }
        { print }
    ' "$1" >"$4"
    [[ $(grep -c "^bore_radius_mm = \($2\|$3\)$" "$4") == 2 ]] || { echo "bores not set in $4" >&2; exit 1; }
}

# run <label> <spec> <torques>: one row per torque.
run() {
    local label=$1 spec=$2 torques=$3
    echo
    echo "$label, \`fmu-build ste <spec with bores> --torque-nm $torques --angles 41\`"
    echo
    echo "| bores r₁ / r₂ (mm) | w (N/mm) | mean STE (µm) | p-p (µm) | k / c_γα | single-zone k / c′ | double/single (ISO 1.75) | zone contrast (mm·µm/N) | contrast / ISO's |"
    echo "|---|---|---|---|---|---|---|---|---|"
    for bores in $BORES; do
        local r1=${bores%/*} r2=${bores#*/}
        local copy="$tmp/$(basename "$spec" .toml)_$r1-$r2.toml"
        with_bores "$spec" "$r1" "$r2" "$copy"
        "$B" ste "$copy" --torque-nm "$torques" --angles 41 --across 4 --profile 8 --rim 4 2>/dev/null | awk -v bores="$r1 / $r2" '
            function num(s) { gsub(/[^0-9.eE+-]/, "", s); return s }
            function after(key,   i) { for (i = 1; i <= NF; i++) if ($i == key) return num($(i + 1)); return "" }
            function flush() { if (w != "") printf "| %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", bores, w, mean, pp, ratio, single, ds, contrast, cratio }
            /^pmor-hertz|^penalty/ {
                flush()
                w = after("=");  mean = after("STE"); pp = after("peak-to-peak")
                ratio = $0; sub(/.*c_γα [0-9.]+ \(ratio /, "", ratio); sub(/\).*/, "", ratio)
                single = ds = contrast = cratio = "–"
            }
            /^  zones:/ {
                single = $0; sub(/.*ISO c′ [0-9.]+ \(ratio /, "", single); sub(/\).*/, "", single)
                ds = after("double/single")
                contrast = $0; sub(/.*\(STE₁ − STE₂\)\/\(F\/b\) /, "", contrast); sub(/ .*/, "", contrast)
                cratio = $0; sub(/.*\/c′ [0-9.]+ \(ratio /, "", cratio); sub(/,.*/, "", cratio)
            }
            END { flush() }
        '
    done
}

if [[ $which == spur || $which == all ]]; then
    run "Spur (Table 4's loads)" examples/kurokawa_spur.toml 20.79,370.251
fi
if [[ $which == helical || $which == all ]]; then
    run "Helical (Table 7's loads)" examples/kurokawa_helical.toml 21.07,917.731
fi
