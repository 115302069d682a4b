#!/usr/bin/env bash
# acados in a virtual environment of its own (never the project's), for the peer benchmarks
# (benchmarks/peers/acados_*.py; issue 46).
#
# Usage:   benchmarks/acados_env.sh                 # make the venv when absent, print its python
#          benchmarks/acados_env.sh python SCRIPT   # run SCRIPT inside it with acados' variables set
#
# The venv goes to ${GTMODEL_ACADOS_VENV:-${XDG_CACHE_HOME:-$HOME/.cache}/gtmodel/acados-venv}.
# It holds the wheel comma-deps-acados (acados 0.2.2 with libacados, HPIPM, BLASFEO, qpOASES and
# the template renderer t_renderer). The wheel vendors a CasADi built for another Python, so
# casadi==3.8.2 is installed over it (--force-reinstall --no-deps). acados' code generation reads
# ACADOS_SOURCE_DIR, ACADOS_PYTHON_INTERFACE_PATH and TERA_PATH, taken here from the acados module's
# DIR, TEMPLATE_DIR and TERA_PATH; LD_LIBRARY_PATH gets its LIB_DIR.
# Exit 3 (and the reason on stderr) when the venv cannot be made (no wheel in the package index).
set -euo pipefail
VENV="${GTMODEL_ACADOS_VENV:-${XDG_CACHE_HOME:-$HOME/.cache}/gtmodel/acados-venv}"
PY="$VENV/bin/python"
if [ ! -x "$PY" ] || ! "$PY" -c "import acados, casadi" >/dev/null 2>&1; then
    mkdir -p "$(dirname "$VENV")"
    python3 -m venv "$VENV" >&2
    if ! "$PY" -m pip install -q comma-deps-acados numpy >&2; then
        echo "acados_env.sh: the wheel comma-deps-acados could not be installed from the package index" >&2
        exit 3
    fi
    "$PY" -m pip install -q --force-reinstall --no-deps "casadi==3.8.2" >&2 || {
        echo "acados_env.sh: casadi==3.8.2 could not be installed over the vendored CasADi" >&2; exit 3; }
fi
eval "$("$PY" - <<'PYEOF'
import acados, shlex
for k, v in (("ACADOS_SOURCE_DIR", acados.DIR), ("ACADOS_PYTHON_INTERFACE_PATH", acados.TEMPLATE_DIR),
             ("TERA_PATH", acados.TERA_PATH)):
    print(f"export {k}={shlex.quote(str(v))}")
print(f"export LD_LIBRARY_PATH={shlex.quote(str(acados.LIB_DIR))}${{LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}}")
PYEOF
)"
if [ $# -eq 0 ]; then
    echo "$PY"
elif [ "$1" = python ]; then
    shift
    exec "$PY" "$@"
else
    exec "$@"
fi
