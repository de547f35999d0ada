#!/usr/bin/env bash
# Idempotent set-up on Debian bookworm (docs/design.md §11): Debian's PETSc/SLEPc/MPI/h5py stack,
# a venv that sees them, and the project installed editable.  Run as root (or with sudo).
# A second run with everything present touches nothing and takes a few seconds.
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES="python3-petsc4py-real python3-slepc4py-real python3-mpi4py python3-h5py-mpi
python3-numpy python3-scipy python3-matplotlib python3-venv python3-setuptools python3-wheel openmpi-bin
python3-pytest python3-pytest-mpi python3-pytest-timeout python3-hypothesis python3-siconos
python3-meshio python3-threadpoolctl"

missing=""
for p in $PACKAGES; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if [ -n "$missing" ]; then
    echo "setup: installing Debian packages:$missing"
    SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends $missing
fi

if [ ! -x .venv/bin/python ] || [ "$(.venv/bin/python -c 'import sys; print(sys.base_prefix)' 2>/dev/null)" != "/usr" ]; then
    echo "setup: creating .venv from /usr/bin/python3 with Debian's site-packages"
    rm -rf .venv
    /usr/bin/python3 -m venv --system-site-packages .venv
fi

# Debian keeps petsc4py/slepc4py outside the default sys.path; a .pth file puts them on
# the venv's path so that no PETSC_DIR/SLEPC_DIR needs exporting (also under mpirun).
site=$(.venv/bin/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
pth="$site/meicp-debian-petsc.pth"
want=$(/usr/bin/python3 -c 'import sys; sys.path.insert(0, "src"); from meicp.petsc import debian_paths; print("\n".join(debian_paths()))')
if [ -z "$want" ]; then echo "setup: Debian's petsc4py/slepc4py not found under /usr/lib" >&2; exit 1; fi
[ -f "$pth" ] && [ "$(cat "$pth")" = "$want" ] || printf '%s\n' "$want" > "$pth"

# editable install only when missing or when pyproject.toml changed since the last one
stamp=.venv/.meicp-installed
if [ ! -f "$stamp" ] || [ pyproject.toml -nt "$stamp" ] || ! .venv/bin/python -c 'import meicp' 2>/dev/null; then
    echo "setup: installing meicp (editable) into .venv"
    .venv/bin/python -m pip install -q --no-deps --no-build-isolation --no-index -e .
    touch "$stamp"
fi
.venv/bin/python -c 'import meicp, petsc4py, slepc4py, mpi4py, h5py; from petsc4py import PETSc; from slepc4py import SLEPc' \
    || { echo "setup: import check failed" >&2; exit 1; }
echo "setup: ok (.venv/bin/meicp)"
