#!/usr/bin/env bash
# HPIPM and BLASFEO built for this machine (issue 46): the casadi wheel's libblasfeo is BLASFEO's
# GENERIC target (plain C kernels); acados' is X64_INTEL_HASWELL.
# - the generated HPIPM step links the static libraries of the folder GTMODEL_HPIPM names instead
#   of the wheel's (gtmodel/codegen/hpipm_source.py);
# - libblasfeo.so.0 in that folder (the same BLASFEO, shared, with the wheel's soname) is what
#   `LD_PRELOAD="$GTMODEL_HPIPM/libblasfeo.so.0"` puts under CasADi's fatrop and hpipm plugins
#   in a process (benchmarks/bench_solve.py measures the offline fatrop solve with it).
#
# Usage:   export GTMODEL_HPIPM="$(benchmarks/hpipm_build.sh [BLASFEO_SOURCE [HPIPM_SOURCE]])"
#
# Sources: the folders given (copied, and the copies checked out at $BLASFEO_VERSION and $HPIPM_COMMIT
# when they are git work trees; the folders themselves are only read), else cloned from https://github.com/giaf/blasfeo and https://github.com/giaf/hpipm
# into the cache. BLASFEO at $BLASFEO_VERSION, the casadi 3.8.2 wheel's (0.1.4.2: the same
# struct blasfeo_dmat and panel height 4 in double as its GENERIC build, so the shared library can
# stand in for the wheel's); HPIPM at $HPIPM_COMMIT: its include/ equals the wheel's HPIPM headers,
# which the generated code is compiled with. BLASFEO TARGET=${BLASFEO_TARGET:-X64_INTEL_HASWELL}
# (AVX2 + FMA; see its Makefile.rule), BLAS_API=0; HPIPM TARGET=${HPIPM_TARGET:-AVX}; both -O2 -fPIC
# static, into ${XDG_CACHE_HOME:-$HOME/.cache}/gtmodel/hpipm-$BLASFEO_TARGET-$BLASFEO_VERSION/
# (printed), with the shared libblasfeo.so.0 linked from the static one. Exit 3 when they cannot be made.
set -euo pipefail
HPIPM_COMMIT=af3ca4757a80dc9658163caeac7dcc0a26f77be3
BLASFEO_VERSION=0.1.4.2
BT="${BLASFEO_TARGET:-X64_INTEL_HASWELL}"
HT="${HPIPM_TARGET:-AVX}"
CACHE="${XDG_CACHE_HOME:-$HOME/.cache}/gtmodel"
OUT="$CACHE/hpipm-$BT-$BLASFEO_VERSION"
fail() { echo "hpipm_build.sh: $*" >&2; exit 3; }
checkout() {  # a git work tree at the given revision (a folder given without git is taken as it is)
    if [ -d "$1/.git" ] || git -C "$1" rev-parse --git-dir >/dev/null 2>&1; then
        git -C "$1" checkout -q "$2" >&2 || fail "$1: cannot check out $2"
    fi
}
if [ ! -f "$OUT/libhpipm.a" ] || [ ! -f "$OUT/libblasfeo.a" ]; then
    BF_SRC="${1:-$CACHE/blasfeo-src}"
    HP_SRC="${2:-$CACHE/hpipm-src}"
    if [ ! -f "$BF_SRC/Makefile.rule" ]; then
        git clone -q https://github.com/giaf/blasfeo "$BF_SRC" >&2 || fail "no BLASFEO source (give its folder)"
    fi
    if [ ! -f "$HP_SRC/Makefile.rule" ]; then
        git clone -q https://github.com/giaf/hpipm "$HP_SRC" >&2 || fail "no HPIPM source (give its folder)"
    fi
    BUILD="$(mktemp -d)"
    trap 'rm -rf "$BUILD"' EXIT
    cp -r "$BF_SRC/." "$BUILD/blasfeo"
    cp -r "$HP_SRC/." "$BUILD/hpipm"
    checkout "$BUILD/blasfeo" "$BLASFEO_VERSION"  # in the copies: a source folder given is only read
    checkout "$BUILD/hpipm" "$HPIPM_COMMIT"
    make -C "$BUILD/blasfeo" -j"$(nproc)" static_library TARGET="$BT" BLAS_API=0 >&2 || fail "BLASFEO's build failed (TARGET=$BT)"
    make -C "$BUILD/hpipm" -j"$(nproc)" static_library TARGET="$HT" BLASFEO_PATH="$BUILD/blasfeo" >&2 \
        || fail "HPIPM's build failed (TARGET=$HT)"
    mkdir -p "$OUT"
    cp "$BUILD/blasfeo/lib/libblasfeo.a" "$BUILD/hpipm/lib/libhpipm.a" "$OUT/"
fi
if [ ! -f "$OUT/libblasfeo.so.0" ]; then
    gcc -shared -o "$OUT/libblasfeo.so.0" -Wl,-soname,libblasfeo.so.0 \
        -Wl,--whole-archive "$OUT/libblasfeo.a" -Wl,--no-whole-archive -lm >&2 || fail "cannot link libblasfeo.so.0"
fi
echo "$OUT"
