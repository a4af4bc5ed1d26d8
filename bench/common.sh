# Shared helpers of bench/denoise.sh and bench/render.sh (sourced, not run).
# A benchmark is never pass/fail: these helpers time commands, keep every run in
# a TSV and summarize repeats as min and median (the machine is shared, so the
# min is the best estimate of the undisturbed time and the median says how
# noisy it was).

# Installs the Debian packages a benchmark needs beyond scripts/install-deps.
bench_require_packages()
{
    local missing=() package
    for package in "$@"; do
        dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
    done
    if ((${#missing[@]})); then
        echo "bench: installing ${missing[*]}" >&2
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
    fi
}

# bench_time TSV LABEL RUN COMMAND...: runs COMMAND under GNU time and appends
# "label run wall_s user_s sys_s max_rss_kb" to TSV. Fails if COMMAND fails.
bench_time()
{
    local tsv=$1 label=$2 run=$3
    shift 3
    local measured
    measured=$(mktemp)
    if ! /usr/bin/time -f "%e %U %S %M" -o "$measured" "$@"; then
        echo "bench: failed: $*" >&2
        cat "$measured" >&2
        rm -f "$measured"
        return 1
    fi
    read -r wall user sys rss < <(tail -n 1 "$measured")
    rm -f "$measured"
    printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$label" "$run" "$wall" "$user" "$sys" "$rss" >>"$tsv"
    printf 'bench: %-28s run %s: %7.2f s wall, %7.2f s CPU, %6.0f MB peak RSS\n' "$label" "$run" "$wall" \
        "$(awk -v u="$user" -v s="$sys" 'BEGIN { print u + s }')" "$(awk -v r="$rss" 'BEGIN { print r / 1024 }')" >&2
}

# bench_stats TSV LABEL COLUMN: "min median" of a column (3 = wall, 6 = RSS KB,
# 7 = CPU = user + sys) over the runs of LABEL.
bench_stats()
{
    awk -F'\t' -v label="$2" -v column="$3" '
        $1 == label { value = (column == 7) ? $4 + $5 : $column; print value }' "$1" |
        sort -g | awk '{ v[NR] = $1 } END {
            if (NR == 0) { print "nan nan"; exit }
            median = (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2
            print v[1], median }'
}

# bench_median_of VALUES...: the median of numbers.
bench_median_of()
{
    printf '%s\n' "$@" | sort -g | awk '{ v[NR] = $1 } END {
        print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'
}

bench_machine()
{
    local cpu
    cpu=$(lscpu | sed -n 's/^Model name: *//p' | head -n 1)
    echo "$(nproc) cores ($cpu), $(free -g | awk '/^Mem:/ { print $2 }') GB RAM, $(uname -sr), $(date -u '+%Y-%m-%d %H:%M UTC'), load average at start $(cut -d' ' -f1-3 /proc/loadavg)"
}
