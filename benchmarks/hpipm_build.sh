#!/usr/bin/env bash
# HPIPM and BLASFEO built for this machine, for the generated HPIPM step (issue 46): the casadi
# wheel's libblasfeo is BLASFEO's GENERIC target (plain C kernels); acados' is X64_INTEL_HASWELL.
# gtmodel links the static libraries of the folder GTMODEL_HPIPM names instead of the wheel's
# (gtmodel/codegen/hpipm_source.py).
#
# Usage:   export GTMODEL_HPIPM="$(benchmarks/hpipm_build.sh [BLASFEO_SOURCE [HPIPM_SOURCE]])"
#
# Sources: the folders given (HPIPM's at commit $HPIPM_COMMIT or one with the same headers), else
# cloned from https://github.com/giaf/blasfeo and https://github.com/giaf/hpipm into the cache.
# HPIPM at $HPIPM_COMMIT: its include/ equals the casadi 3.8.2 wheel's HPIPM headers, which the
# generated code is compiled with. BLASFEO TARGET=${BLASFEO_TARGET:-X64_INTEL_HASWELL} (AVX2 + FMA;
# see its Makefile.rule), BLAS_API=0; HPIPM TARGET=${HPIPM_TARGET:-AVX}; both -O2 -fPIC static, into
# ${XDG_CACHE_HOME:-$HOME/.cache}/gtmodel/hpipm-$BLASFEO_TARGET/ (printed). Exit 3 when they cannot be made.
set -euo pipefail
HPIPM_COMMIT=af3ca4757a80dc9658163caeac7dcc0a26f77be3
BT="${BLASFEO_TARGET:-X64_INTEL_HASWELL}"
HT="${HPIPM_TARGET:-AVX}"
CACHE="${XDG_CACHE_HOME:-$HOME/.cache}/gtmodel"
OUT="$CACHE/hpipm-$BT"
fail() { echo "hpipm_build.sh: $*" >&2; exit 3; }
if [ ! -f "$OUT/libhpipm.a" ] || [ ! -f "$OUT/libblasfeo.a" ]; then
    BF_SRC="${1:-$CACHE/blasfeo-src}"
    HP_SRC="${2:-$CACHE/hpipm-src}"
    if [ ! -f "$BF_SRC/Makefile.rule" ]; then
        git clone -q https://github.com/giaf/blasfeo "$BF_SRC" >&2 || fail "no BLASFEO source (give its folder)"
    fi
    if [ ! -f "$HP_SRC/Makefile.rule" ]; then
        git clone -q https://github.com/giaf/hpipm "$HP_SRC" >&2 && git -C "$HP_SRC" checkout -q "$HPIPM_COMMIT" >&2 \
            || fail "no HPIPM source at $HPIPM_COMMIT (give its folder)"
    fi
    BUILD="$(mktemp -d)"
    trap 'rm -rf "$BUILD"' EXIT
    cp -r "$BF_SRC/." "$BUILD/blasfeo"
    cp -r "$HP_SRC/." "$BUILD/hpipm"
    make -C "$BUILD/blasfeo" -j"$(nproc)" static_library TARGET="$BT" BLAS_API=0 >&2 || fail "BLASFEO's build failed (TARGET=$BT)"
    make -C "$BUILD/hpipm" -j"$(nproc)" static_library TARGET="$HT" BLASFEO_PATH="$BUILD/blasfeo" >&2 \
        || fail "HPIPM's build failed (TARGET=$HT)"
    mkdir -p "$OUT"
    cp "$BUILD/blasfeo/lib/libblasfeo.a" "$BUILD/hpipm/lib/libhpipm.a" "$OUT/"
fi
echo "$OUT"
