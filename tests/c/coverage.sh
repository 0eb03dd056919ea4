#!/bin/sh
# Line and branch coverage of fmu_src/ under the C suite and the Python tests that drive
# the FMU's binary (issue 21).  gcc --coverage (-O0), gcov's JSON, summed by
# tests/c/coverage_report.py (Python's standard library only: no gcovr or lcov needed).
#
#   tests/c/coverage.sh            # from the repository root; about 10-15 min on one core
#
# What runs (the suite's own arguments, tests/test_c_sanitizers.py, without sanitizers):
#   - every C driver of tests/c/ (test_core, test_fmi2, test_fmi3, test_time, test_replan,
#     test_shaper, test_math, test_plan_libm) against one instrumented build of fmu_src/;
#   - the gcc replay of the fuzz corpus (tests/fuzz/corpus/*, tests/test_fuzz_corpus.py);
#   - the Python tests that load the FMU binary ($COV_PYTEST, default the FMU tests below),
#     their FMUs built with --coverage (DJL_TEST_FMU_CFLAGS, tests/conftest.py).
# Prints every line of fmu_src/ left uncovered, per file figures, and last:
#   lines: P %  branches: Q %
# Environment: COV_DIR (work folder, default /tmp/djl-coverage, emptied first),
# COV_PYTEST ("" to skip the Python tests), COV_QUICK=1 (small argument sets, a smoke run).
set -eu
cd "$(dirname "$0")/../.."
ROOT=$(pwd)
COV=${COV_DIR:-/tmp/djl-coverage}
PY=${PYTHON:-python}
COV_PYTEST=${COV_PYTEST-"tests/test_fmu_interface.py tests/test_fmu_commands.py tests/test_fmu_shaper.py tests/test_hostile_inputs.py tests/test_fmu_artefacts.py tests/test_fmu_table.py tests/test_fmu_cmd.py tests/test_fmu_queue.py tests/test_program_engines.py"}
FMI=$($PY -c 'from harness.fmu.build import fmi_include_dir; print(fmi_include_dir())')
rm -rf "$COV"
mkdir -p "$COV/obj" "$COV/bin" "$COV/fmu2" "$COV/fmu3"
CFLAGS="-std=c99 -O0 -g --coverage -Wall -Wextra -Wpedantic -Werror -Ifmu_src -I$FMI"
log() { echo "coverage.sh: $*" >&2; }

# one instrumented build of fmu_src/, every driver linked against it (counts add up)
for src in fmu_src/*.c; do
    name=$(basename "$src" .c)
    # shellcheck disable=SC2086
    gcc $CFLAGS -c "$src" -o "$COV/obj/$name.o"
done
CORE="$COV/obj/djl_validate.o $COV/obj/djl_segment.o $COV/obj/djl_motion.o $COV/obj/djl_replan.o
      $COV/obj/djl_eval.o $COV/obj/djl_shaper.o $COV/obj/djl_table.o"
FMU="$COV/obj/fmu_base.o $COV/obj/fmu_model.o $COV/obj/fmu_instance.o"
link() { # name, sources (driver), objects
    out=$1
    shift
    # shellcheck disable=SC2086
    gcc $CFLAGS -dumpdir "$COV/bin/$out-" "$@" -o "$COV/bin/$out" -lm
}
link test_core tests/c/test_core.c $CORE
link test_fmi2 tests/c/test_fmi2.c "$COV/obj/fmi2.o" $FMU $CORE
link test_fmi3 tests/c/test_fmi3.c "$COV/obj/fmi3.o" $FMU $CORE
link test_time tests/c/test_time.c "$COV/obj/fmi2.o" $FMU $CORE
link test_math tests/c/test_math.c
link test_replan tests/c/test_replan.c $CORE
link test_shaper tests/c/test_shaper.c "$COV/obj/fmi2.o" $FMU $CORE
link test_plan_libm tests/c/test_plan_libm.c tests/c/core_libm.c $CORE
link replay_fmi tests/fuzz/fuzz_fmi.c tests/fuzz/replay.c "$COV/obj/fmi2.o" "$COV/obj/fmi3.o" $FMU $CORE
link replay_state tests/fuzz/fuzz_state.c tests/fuzz/replay.c "$COV/obj/fmi2.o" $FMU $CORE
link replay_plan tests/fuzz/fuzz_plan.c tests/fuzz/replay.c $CORE

if [ "${COV_QUICK:-0}" = 1 ]; then
    ARGS_CORE="3000 7"; ARGS_FMI2="1000 100"; ARGS_TIME="2000"; ARGS_MATH="1000 7"
    ARGS_REPLAN="40 7"; ARGS_SHAPER="100 7 20000"; ARGS_LIBM="300 7"
else
    ARGS_CORE="300000 7"; ARGS_FMI2="100000 10000"; ARGS_TIME="200000"; ARGS_MATH="100000 7"
    ARGS_REPLAN="400 7"; ARGS_SHAPER="1000 7 20000"; ARGS_LIBM="30000 7"
fi
run() { # name, arguments: the suite's checks pass under coverage too
    name=$1
    shift
    log "running $name ($# arguments)"
    "$COV/bin/$name" "$@" > "$COV/$name.out" 2>&1 || { cat "$COV/$name.out" >&2; exit 1; }
}
# shellcheck disable=SC2086
{
    run test_core $ARGS_CORE
    run test_fmi2 $ARGS_FMI2
    run test_fmi3
    run test_time $ARGS_TIME
    run test_math $ARGS_MATH
    run test_replan $ARGS_REPLAN
    run test_shaper $ARGS_SHAPER
    run test_plan_libm $ARGS_LIBM
    run replay_fmi tests/fuzz/corpus/fmi/*
    run replay_state tests/fuzz/corpus/state/*
    run replay_plan tests/fuzz/corpus/plan/*
}

if [ -n "$COV_PYTEST" ]; then
    log "running pytest $COV_PYTEST (FMUs built with --coverage)"
    # one process (-n 0): workers building the FMU into the same gcov folder would mix
    # the notes of one build with the counts of another ("stamp mismatch")
    # shellcheck disable=SC2086
    DJL_TEST_FMU_CFLAGS="-O0 --coverage -dumpdir $COV/fmu{fmi}/" \
        $PY -m pytest -q -n 0 -p no:cacheprovider $COV_PYTEST > "$COV/pytest.out" 2>&1 ||
        { tail -30 "$COV/pytest.out" >&2; exit 1; }
fi

$PY tests/c/coverage_report.py --root "$ROOT" "$COV/obj" "$COV/bin" "$COV/fmu2" "$COV/fmu3"
