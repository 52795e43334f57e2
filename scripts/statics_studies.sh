#!/usr/bin/env bash
# Mesh independence, the paper's Eq. 20 beside Weber, and n_sv / STE against p_en for the PMOR-Hertz
# statics (issue 4), at 392 N/mm (Tables 4 and 7). One markdown row per run; BENCHMARKS.md quotes it.
# Usage: scripts/statics_studies.sh [spur|helical|all]   (release build of fmu-build first)
set -euo pipefail
cd "$(dirname "$0")/.."
B=./target/release/fmu-build
which=${1:-all}

# run <label> <spec> <torque> <fmu-build ste options...>: one table row.
run() {
    local label=$1 spec=$2 torque=$3
    shift 3
    local out
    # The coarse 4/8/4 mesh the quoted figures were measured on (ste's default is now the build's).
    if ! out=$("$B" ste "$spec" --torque-nm "$torque" --angles 21 --across 4 --profile 8 --rim 4 "$@" 2>&1); then
        echo "| $label | ${out##*error: } |||||"
        return
    fi
    awk -v label="$label" '
        /loadable nodes/ { n = n (n ? " / " : "") $3; nsv = nsv (nsv ? " / " : "") $8 }
        /mean STE/ { for (i = 1; i <= NF; i++) { if ($i == "STE") mean = $(i + 1); if ($i == "peak-to-peak") pp = $(i + 1) } }
        /^reduction/ { red = $2; per = $0; sub(/.*\(/, "", per); sub(/ s per case.*/, "", per) }
        END { printf "| %s | %s | %s | %s | %s | %s | %s |\n", label, n, nsv, mean, pp, red, per }
    ' <<<"$out"
}

header() {
    echo
    echo "$1"
    echo
    echo "| variant | loadable nodes (gear 1 / 2) | n_sv | mean STE (µm) | p-p (µm) | reduction (s) | per case (s, one thread) |"
    echo "|---|---|---|---|---|---|---|"
}

if [[ $which == spur || $which == all ]]; then
    S=examples/kurokawa_spur.toml T=370.251
    header "Spur, T₁ = $T N·m (392 N/mm), default mesh 4/8/4, 21 angles"
    for law in "" --eq20; do
        for slices in 4 8; do run "slices $slices, h 3 mm, p_en 99.9 % ${law:-(Weber)}" $S $T --slices $slices --p-en 0.999 $law; done
        for h in 2.5 4 5 6; do run "slices 4, h $h mm, p_en 99.9 % ${law:-(Weber)}" $S $T --depth-mm $h --p-en 0.999 $law; done
    done
    for p in 0.9 0.99 0.999 0.9999; do run "slices 4, h 3 mm, p_en $p" $S $T --p-en $p; done
fi

if [[ $which == helical || $which == all ]]; then
    S=examples/kurokawa_helical.toml T=917.731
    header "Helical, T₁ = $T N·m (Table 7's 392 N/mm), mesh 4/8/4, 21 angles"
    for law in "" --eq20; do
        for slices in 8 16 32; do run "slices $slices, h 3 mm, p_en 99.9 % ${law:-(Weber)}" $S $T --slices $slices --p-en 0.999 $law; done
        for h in 4 5 6; do run "slices 16, h $h mm, p_en 99.9 % ${law:-(Weber)}" $S $T --slices 16 --depth-mm $h --p-en 0.999 $law; done
    done
    for p in 0.9 0.99 0.999 0.9999; do run "slices 16, h 3 mm, p_en $p" $S $T --slices 16 --p-en $p; done
fi
