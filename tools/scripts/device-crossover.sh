#!/usr/bin/env bash
# device-crossover.sh - where the GPU starts to pay on this machine: whole `reconstruct` processes
# of generated drops, CPU against CUDA, at several thread counts (the runs behind --device auto's
# rule, README "Which device"). Runs alternate CPU / CUDA; each cell is the median of --runs.
# Prints a Markdown table (seconds, CPU / CUDA; bold where CUDA is faster) and where each thread
# count crosses over, next to the rule's line, 1M x (threads / 4)^1.45.
#
#   bash tools/scripts/device-crossover.sh                          # 0.25M-8M, 4/8/16 threads
#   bash tools/scripts/device-crossover.sh --sizes 1000000,4000000 --threads 16 --runs 5
#   bash tools/scripts/device-crossover.sh --fluidsurf ./fluidsurf --dir /scratch
set -euo pipefail

bin="$(dirname "$0")/../../build/fluidsurf"
sizes=250000,500000,1000000,2000000,4000000,8000000
threads=4,8,16
runs=3
dir=/tmp
while [ $# -gt 0 ]; do
    case "$1" in
    --fluidsurf) bin=$2; shift 2 ;;
    --sizes) sizes=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --runs) runs=$2; shift 2 ;;
    --dir) dir=$2; shift 2 ;;
    -h | --help) sed -n '2,10p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "device-crossover: unknown option '$1' (--help)" >&2; exit 2 ;;
    esac
done
[ -x "$bin" ] || { echo "device-crossover: no fluidsurf program at $bin (--fluidsurf)" >&2; exit 2; }
case "$runs" in '' | *[!0-9]* | 0) echo "device-crossover: --runs must be a positive number" >&2; exit 2 ;; esac
if ! "$bin" reconstruct --help >/dev/null 2>&1; then
    echo "device-crossover: $bin does not run" >&2; exit 2
fi
IFS=, read -r -a sizeList <<<"$sizes"
IFS=, read -r -a threadList <<<"$threads"
work=$(mktemp -d "$dir/device-crossover.XXXXXX")
trap 'rm -rf "$work"' EXIT

seconds() { # the wall time of one run, or "failed"
    local start end
    start=$(date +%s.%N)
    "$@" >/dev/null 2>"$work/err" || { echo failed; return; }
    end=$(date +%s.%N)
    awk -v a="$start" -v b="$end" 'BEGIN { printf "%.3f", b - a }'
}
median() { tr ' ' '\n' | grep -v '^$' | sort -n | awk '{ v[NR] = $1 } END { print (NR ? v[int((NR + 1) / 2)] : "failed") }'; }

for n in "${sizeList[@]}"; do
    echo "device-crossover: generating a drop of $n particles" >&2
    "$bin" generate drop -n "$n" -r 0.01 -o "$work/drop_$n.xyz" >/dev/null
done
if ! "$bin" reconstruct "$work/drop_${sizeList[0]}.xyz" -r 0.01 -o "$work/probe.ply" -q --device cuda 2>"$work/err"; then
    echo "device-crossover: --device cuda does not run here: $(tail -1 "$work/err")" >&2
    exit 1
fi

header="| particles |"; rule="|---|"
for t in "${threadList[@]}"; do header="$header $t threads: CPU / CUDA |"; rule="$rule---|"; done
echo "$header"; echo "$rule"
declare -A crossing
for n in "${sizeList[@]}"; do
    row="| $n |"
    for t in "${threadList[@]}"; do
        cpu="" gpu=""
        for ((k = 0; k < runs; ++k)); do
            args=(reconstruct "$work/drop_$n.xyz" -r 0.01 -o "$work/out.ply" -q -j "$t")
            cpu="$cpu $(seconds "$bin" "${args[@]}" --device cpu)"
            gpu="$gpu $(seconds "$bin" "${args[@]}" --device cuda)"
        done
        c=$(echo "$cpu" | median) g=$(echo "$gpu" | median)
        if awk -v c="$c" -v g="$g" 'BEGIN { exit !(g + 0 < c + 0) }'; then
            row="$row $c / **$g** |"
            [ -n "${crossing[$t]:-}" ] || crossing[$t]=$n
        else
            row="$row $c / $g |"
        fi
    done
    echo "$row"
done
echo
for t in "${threadList[@]}"; do
    line=$(awk -v t="$t" 'BEGIN { printf "%.2gM", 1e6 * ((t < 1 ? 1 : t) / 4) ^ 1.45 / 1e6 }')
    if [ -n "${crossing[$t]:-}" ]; then
        echo "- $t threads: CUDA first faster at ${crossing[$t]} particles; the rule's line: $line"
    else
        echo "- $t threads: CUDA faster at none of these sizes; the rule's line: $line"
    fi
done
