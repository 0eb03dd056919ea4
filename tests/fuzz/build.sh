#!/bin/sh
# Builds the fuzz harnesses of tests/fuzz/ with libFuzzer, AddressSanitizer and UBSan
# (clang; Debian: apt-get install clang libclang-rt-14-dev), into $OUT (default
# /tmp/djl-fuzz): fuzz_fmi, fuzz_state, fuzz_plan.  The fuzzers are tools run on
# demand, not part of the suite (tests/test_fuzz_corpus.py replays the corpus with
# gcc).  Run one at a time, e.g. (docs/fuzzing.md):
#
#   tests/fuzz/build.sh && nice -n 15 /tmp/djl-fuzz/fuzz_fmi -max_total_time=1800 \
#       /tmp/djl-fuzz/corpus_fmi tests/fuzz/corpus/fmi
#
# Coverage guidance: edge counters, without libFuzzer's comparison tracing (trace-cmp),
# unless FUZZ_TRACE_CMP=1.  The integer comparisons the FMU makes are mostly djl_math.h's
# tests of the IEEE 754 encoding, inlined everywhere: their callbacks took 48 % of
# fuzz_plan's time and 20 % of fuzz_fmi's (perf) and guided nothing (the harnesses decode
# choices by table index).  Measured from an
# empty corpus, same seed, 120-150 s each, the two builds side by side (docs/fuzzing.md,
# "Fuzz harnesses"): without the tracing 1.5-3.6x the inputs/s and more edges reached.
# The state checksum is built without ASan/UBSan (tests/fuzz/sanitize_ignore.txt says why).
set -eu
cd "$(dirname "$0")/../.."
OUT=${OUT:-/tmp/djl-fuzz}
CC=${CC:-clang}
FMI=$(python -c 'from harness.fmu.build import fmi_include_dir; print(fmi_include_dir())')
mkdir -p "$OUT"
CMP=-fno-sanitize-coverage=trace-cmp
[ "${FUZZ_TRACE_CMP:-0}" = 1 ] && CMP=
FLAGS="-std=c99 -g -O1 -Wall -Wextra -Wpedantic -Werror -Ifmu_src -I$FMI
       -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
       $CMP -fsanitize-coverage-ignorelist=tests/fuzz/coverage_ignore.txt
       -fsanitize-ignorelist=tests/fuzz/sanitize_ignore.txt"
CORE="fmu_src/djl_validate.c fmu_src/djl_segment.c fmu_src/djl_motion.c fmu_src/djl_replan.c
      fmu_src/djl_eval.c fmu_src/djl_shaper.c fmu_src/djl_table.c"
FMU="fmu_src/fmu_base.c fmu_src/fmu_model.c fmu_src/fmu_instance.c"
# shellcheck disable=SC2086
# fuzz_fmi hands the FMU's big blocks out from a pool (FUZZ_POOL, see fuzz_fmi.c): FMI 2's
# through its callbacks, FMI 3's by renaming calloc and free in fmi3.c for this build only
$CC $FLAGS -DFUZZ_POOL -Dcalloc=fuzz_calloc -Dfree=fuzz_free -c fmu_src/fmi3.c \
    -o "$OUT/fmi3_pool.o"
$CC $FLAGS -DFUZZ_POOL tests/fuzz/fuzz_fmi.c fmu_src/fmi2.c "$OUT/fmi3_pool.o" $FMU $CORE \
    -lm -o "$OUT/fuzz_fmi"
# shellcheck disable=SC2086
$CC $FLAGS tests/fuzz/fuzz_state.c fmu_src/fmi2.c $FMU $CORE -lm -o "$OUT/fuzz_state"
# shellcheck disable=SC2086
$CC $FLAGS tests/fuzz/fuzz_plan.c $CORE -lm -o "$OUT/fuzz_plan"
echo "built $OUT/fuzz_fmi $OUT/fuzz_state $OUT/fuzz_plan"
