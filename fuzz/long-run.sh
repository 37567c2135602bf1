#!/bin/sh
# A long run of one fuzz target, as the results in README.md were made: no sanitizer (the
# crate forbids `unsafe`), no comparison tracing (2x the executions per second; the dictionary
# and the seed corpus supply the magic bytes), 10^7 executions, then libFuzzer's final stats.
#
#   ./long-run.sh decode            # or push, header, roundtrip; a second argument: executions
#
# Needs cargo-fuzz (`cargo install cargo-fuzz`). Seeds with seed.sh when the corpus is empty.
# One run per core: each is one process.
set -e
cd "$(dirname "$0")"
t=${1:?usage: long-run.sh <decode|push|header|roundtrip> [executions]}
runs=${2:-10000000}
case $t in
    header|roundtrip) len=512 ;;
    *) len=1024 ;;
esac
[ -n "$(find "corpus/$t" -maxdepth 1 -type f 2>/dev/null | head -n 1)" ] || ./seed.sh
mkdir -p "artifacts/$t"
RUSTC_BOOTSTRAP=1 cargo fuzz build -O -s none --no-trace-compares "$t"
exec "target/x86_64-unknown-linux-gnu/release/$t" "corpus/$t" -dict=qcs.dict \
    -max_len=$len -timeout=600 -rss_limit_mb=2048 -runs="$runs" -print_final_stats=1 \
    -artifact_prefix="artifacts/$t/"
