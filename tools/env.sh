#!/usr/bin/env bash
# tapecoil's environment: find a usable FEniCSx Python, or build a Debian root that has one,
# and run commands in it.
#
#   tools/env.sh setup          provision (idempotent; a no-op when everything is in place)
#   tools/env.sh run CMD ARG..  run a command in the environment (cwd kept)
#   tools/env.sh shell          interactive shell in the environment
#   tools/env.sh info           print which environment is in use
#
# Selection (first that applies):
#   TAPECOIL_ENV=host     use $PYTHON (default python3) as it is; fail if it lacks DOLFINx >= 0.9
#   TAPECOIL_ENV=chroot   always use the Debian root
#   (unset)               host if $PYTHON imports dolfinx >= 0.9, petsc4py, mpi4py and gmsh, else chroot
# The Debian root lives in .env/$TAPECOIL_SUITE (default trixie; sid has DOLFINx 0.11), is
# git-ignored, and is entered through a private mount namespace so that nothing stays mounted.
set -euo pipefail

PROJECT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)
SUITE=${TAPECOIL_SUITE:-trixie}
MIRROR=${TAPECOIL_MIRROR:-http://deb.debian.org/debian}
PYTHON=${PYTHON:-python3}
ROOT=$PROJECT/.env/$SUITE
VENV=/opt/tapecoil-venv # inside the root
MIN_FREE_GB=${TAPECOIL_MIN_FREE_GB:-8}

# Debian packages of the root. Changing this list re-runs apt inside an existing root.
# libopenblas0-serial replaces the reference BLAS that PETSc and MUMPS are linked against
# (Debian's default): a Newton iteration of the default-mesh coiling run took 0.248 s with the
# reference BLAS and 0.169 s with OpenBLAS on one rank, 0.160 s and 0.113 s on two.
# Sphinx, MyST, furo, jupytext and MathJax build the documentation (make docs); chromium
# renders it headless in its check (make docs-check).
PACKAGES=(
  python3-dolfinx-real python3-petsc4py-real python3-mpi4py python3-gmsh
  python3-adios4dolfinx python3-scipy python3-matplotlib python3-pyvista python3-meshio
  python3-tqdm python3-rich python3-pytest python3-imageio
  libopenblas0-serial
  python3-pip python3-venv python3-setuptools
  openmpi-bin xvfb xauth make git ca-certificates
  python3-sphinx python3-myst-parser furo python3-jupytext libjs-mathjax chromium
)

die() {
  echo "tapecoil env: $*" >&2
  exit 1
}
say() { echo "tapecoil env: $*" >&2; }

# --- host Python -------------------------------------------------------------------------
host_python_ok() {
  command -v "$PYTHON" >/dev/null 2>&1 || return 1
  "$PYTHON" - <<'EOF' >/dev/null 2>&1
import dolfinx, petsc4py, mpi4py, gmsh  # noqa: F401
major, minor = (int(p) for p in dolfinx.__version__.split(".")[:2])
raise SystemExit(0 if (major, minor) >= (0, 9) else 1)
EOF
}

mode() {
  case "${TAPECOIL_ENV:-}" in
    host)
      host_python_ok || die "TAPECOIL_ENV=host but '$PYTHON' cannot import dolfinx >= 0.9, petsc4py, mpi4py and gmsh"
      echo host
      ;;
    chroot) echo chroot ;;
    "") if host_python_ok; then echo host; else echo chroot; fi ;;
    *) die "TAPECOIL_ENV must be 'host', 'chroot' or unset (got '$TAPECOIL_ENV')" ;;
  esac
}

stamp_of() { # a content hash, so that a change to its inputs re-runs the step
  printf '%s\n' "$@" | sha256sum | cut -c1-16
}

setup_host() {
  local stamp="$PROJECT/.env/host-$(stamp_of "$(command -v "$PYTHON")" "$(cat "$PROJECT/pyproject.toml")")"
  [[ -e $stamp ]] && return 0
  say "installing tapecoil (editable) into $("$PYTHON" -c 'import sys; print(sys.prefix)')"
  "$PYTHON" -m pip install --quiet -e "$PROJECT[test]" || die "pip install -e . failed in the host Python"
  mkdir -p "$PROJECT/.env" && touch "$stamp"
}

# --- Debian root -------------------------------------------------------------------------
check_can_provision() {
  [[ $(id -u) == 0 ]] || die "building the Debian $SUITE root needs root (debootstrap, chroot, mount namespaces); run as root, or install DOLFINx >= 0.9 and set PYTHON=/path/to/python"
  command -v unshare >/dev/null && command -v chroot >/dev/null || die "unshare and chroot (util-linux, coreutils) are required"
  mkdir -p "$PROJECT/.env"
  local free_kb
  free_kb=$(df -Pk "$PROJECT/.env" | awk 'NR==2 {print $4}')
  ((free_kb >= MIN_FREE_GB * 1024 * 1024)) ||
    die "disk full: the Debian root needs about ${MIN_FREE_GB} GB free under $PROJECT/.env, only $((free_kb / 1024)) MB are"
  # (curl or wget, whichever the host has; without either, debootstrap reports the network)
  local release=$MIRROR/dists/$SUITE/Release
  if command -v curl >/dev/null; then
    curl -fsS --max-time 20 -o /dev/null "$release" 2>/dev/null
  elif command -v wget >/dev/null; then
    wget -q --timeout=20 -O /dev/null "$release" 2>/dev/null
  fi || die "registry unreachable: cannot fetch $release (set TAPECOIL_MIRROR, or check the network)"
  if ! command -v debootstrap >/dev/null; then
    say "installing debootstrap"
    { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq debootstrap; } >/dev/null 2>&1 ||
      die "debootstrap is missing and 'apt-get install debootstrap' failed"
  fi
}

assert_nothing_mounted_in_root() {
  if grep -q " $ROOT/" /proc/mounts; then
    die "something is still mounted below $ROOT; refusing to touch it (umount it first)"
  fi
}

# Run a command inside the root with /dev, /proc, /sys and the project bound at its own path;
# the private mount namespace dies with the command and takes every mount with it. Only a
# fixed environment and the TAPECOIL_*, PYTEST_ADDOPTS and CI variables cross into the root.
in_root() {
  local cwd=$1 var
  shift
  [[ $(id -u) == 0 ]] || die "entering the Debian $SUITE root needs root (mount namespace, chroot); run as root, or set PYTHON to a Python with DOLFINx >= 0.9"
  local envargs=(
    HOME=/root LANG=C.UTF-8 "TERM=${TERM:-dumb}" "PATH=$VENV/bin:/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin"
    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg PYVISTA_OFF_SCREEN=true
    OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl=self,vader
    OMPI_MCA_rmaps_base_oversubscribe=1
    "TAPECOIL_IN_ENV=$SUITE"
  )
  for var in $(compgen -e); do
    [[ $var == TAPECOIL_* || $var == PYTEST_ADDOPTS || $var == CI ]] && [[ $var != TAPECOIL_IN_ENV ]] && envargs+=("$var=${!var}")
  done
  unshare -m --propagation private -- /bin/sh -c '
    R=$1 P=$2; shift 2
    mount --rbind /dev "$R/dev" && mount -t proc proc "$R/proc" && mount --rbind /sys "$R/sys" &&
      mkdir -p "$R$P" && mount --bind "$P" "$R$P" || { echo "tapecoil env: mounting into $R failed" >&2; exit 97; }
    exec chroot "$R" /usr/bin/env -i "$@"
  ' sh "$ROOT" "$PROJECT" "${envargs[@]}" /bin/sh -c "$ENTER" sh "$cwd" "$PROJECT" "$@"
}

# Inside the root (sh): go to the directory $1 and run the command after $2, the project
# directory, which is all of this machine the root sees.
ENTER='cd "$1" 2>/dev/null || {
  echo "tapecoil env: $1 is not visible in the environment: only paths inside the project directory $2 are; work from inside it (copy what you need there, e.g. into $2/scratch/)" >&2
  exit 1
}
shift 2
exec "$@"'

# The words of a command (split at blanks, and after an "=") that name a file or directory of
# this machine outside the project which the Debian root does not have at the same place:
# inside the environment they do not exist. FROM: the directory relative words are read from
# here; INSIDE: the one the command runs in inside the root. /dev, /proc and /sys are bound
# into the root (in_root), so the machine's own are seen there.
invisible_paths() {
  local from=$1 inside=$2 arg word candidate host there real
  local -a words
  shift 2
  for arg in "$@"; do
    read -r -a words <<<"$arg" || true
    for word in "${words[@]}"; do
      word=${word//[\'\"]/}
      for candidate in "$word" "${word#*=}"; do
        [[ -n $candidate && $candidate != -* ]] || continue
        if [[ $candidate == /* ]]; then
          host=$candidate there=$ROOT$candidate
        else
          host=$from/$candidate there=$ROOT$inside/$candidate
        fi
        [[ -e $host ]] || continue
        real=$(realpath -- "$host")
        case $real in /dev | /dev/* | /proc | /proc/* | /sys | /sys/*) continue ;; esac
        [[ $real == "$PROJECT" || $real == "$PROJECT"/* || -e $there ]] || echo "$candidate"
        [[ $candidate == "$word" && $word == *=* ]] || break
      done
    done
  done | sort -u
}

# Refuse a command that names files the environment cannot see, saying what to do instead.
check_visible() {
  local missing
  missing=$(invisible_paths "$@")
  [[ -z $missing ]] && return 0
  die "the command names $(echo $missing | sed 's/ /, /g'), outside the project directory $PROJECT: only paths inside the project directory are visible in the environment (the Debian root has its own filesystem). Copy what the command needs into the project, e.g. into $PROJECT/scratch/, and name it there (make run CMD=\"python3 scratch/my_script.py\")."
}

# Snapshot mirrors serve Release files past their Valid-Until date (sid's expire within
# days); the archive signatures are still checked. dpkg skips its fsync calls
# (--force-unsafe-io): unpacking the root's ~700 packages is the longest part of provisioning,
# and a root left damaged by a power loss meanwhile is thrown away (make clean-env), not repaired.
root_apt() {
  in_root / /bin/sh -c "DEBIAN_FRONTEND=noninteractive apt-get -o Acquire::Check-Valid-Until=false -o Dpkg::Options::=--force-unsafe-io $*"
}

setup_root() {
  local boot_stamp=$ROOT/.tapecoil-debootstrap
  local pkg_stamp=$ROOT/.tapecoil-packages-$(stamp_of "${PACKAGES[@]}")
  local pip_stamp=$ROOT/.tapecoil-editable-$(stamp_of "$PROJECT" "$(cat "$PROJECT/pyproject.toml")")
  [[ -e $boot_stamp && -e $pkg_stamp && -e $pip_stamp ]] && return 0

  check_can_provision
  if [[ ! -e $boot_stamp ]]; then
    assert_nothing_mounted_in_root
    rm -rf "$ROOT" # a half-built root from an interrupted run
    say "debootstrap $SUITE into ${ROOT#"$PROJECT"/} (about a minute)"
    debootstrap --variant=minbase "$SUITE" "$ROOT" "$MIRROR" >"$PROJECT/.env/debootstrap-$SUITE.log" 2>&1 ||
      die "debootstrap failed ($(tail -n 1 "$PROJECT/.env/debootstrap-$SUITE.log")); full log in .env/debootstrap-$SUITE.log"
    touch "$boot_stamp"
  fi
  cp /etc/resolv.conf "$ROOT/etc/resolv.conf" 2>/dev/null || true
  if [[ ! -e $pkg_stamp ]]; then
    say "installing FEniCSx and tools from Debian $SUITE (a few minutes, about 4 GB)"
    {
      root_apt "update -q" && root_apt "install -y -q --no-install-recommends ${PACKAGES[*]}"
    } >"$PROJECT/.env/apt-$SUITE.log" 2>&1 || {
      grep -qi "no space left" "$PROJECT/.env/apt-$SUITE.log" && die "disk full while installing packages (see .env/apt-$SUITE.log)"
      die "apt-get install in the $SUITE root failed: $(grep -E '^E:' "$PROJECT/.env/apt-$SUITE.log" | head -n 2 | tr '\n' ' ')(log: .env/apt-$SUITE.log)"
    }
    root_apt "clean" >/dev/null 2>&1 || true
    rm -f "$ROOT"/.tapecoil-packages-*
    touch "$pkg_stamp"
  fi
  if [[ ! -e $pip_stamp ]]; then
    say "installing tapecoil (editable) in the $SUITE root"
    # The host's local certificate authorities (a proxy's, a company's) must be trusted inside
    # the root too, or pip cannot reach the package index through them.
    if [[ -d /usr/local/share/ca-certificates ]]; then
      cp -a /usr/local/share/ca-certificates/. "$ROOT/usr/local/share/ca-certificates/"
      in_root / update-ca-certificates >/dev/null 2>&1 || true
    fi
    in_root "$PROJECT" /bin/sh -c "
      set -e
      [ -x $VENV/bin/python ] || python3 -m venv --system-site-packages $VENV
      $VENV/bin/pip install --quiet --no-deps --no-build-isolation -e '$PROJECT'
      $VENV/bin/pip install --quiet ruff || echo 'tapecoil env: ruff not installable (lint unavailable)' >&2
    " >"$PROJECT/.env/pip-$SUITE.log" 2>&1 || die "editable install failed; log in .env/pip-$SUITE.log"
    rm -f "$ROOT"/.tapecoil-editable-*
    touch "$pip_stamp"
  fi
  say "environment ready: Debian $SUITE root, $(in_root / python3 -c 'import dolfinx; print("DOLFINx", dolfinx.__version__)')"
}

# --- commands ----------------------------------------------------------------------------

# sourced (the tests read the functions above): define them and do nothing
[[ ${BASH_SOURCE[0]} == "$0" ]] || return 0

cmd=${1:-}
shift || true
MODE=$(mode) || exit 1
case "$cmd" in
  setup)
    if [[ $MODE == host ]]; then setup_host; else setup_root; fi
    ;;
  run)
    (($# > 0)) || die "usage: tools/env.sh run CMD [ARGS...]"
    if [[ $MODE == host ]]; then
      setup_host
      exec "$@"
    fi
    setup_root
    here=$(pwd -P) cwd=$(pwd -P)
    if [[ $cwd != "$PROJECT" && $cwd != "$PROJECT"/* ]]; then
      cwd=$PROJECT
      say "$here is outside the project, which is all the environment sees: running in $PROJECT"
    fi
    check_visible "$here" "$cwd" "$@"
    in_root "$cwd" "$@"
    ;;
  shell)
    if [[ $MODE == host ]]; then exec "${SHELL:-/bin/bash}"; fi
    setup_root
    in_root "$(pwd -P)" /bin/bash
    ;;
  info)
    if [[ $MODE == host ]]; then
      echo "host Python: $(command -v "$PYTHON") ($("$PYTHON" -c 'import dolfinx; print("DOLFINx", dolfinx.__version__)'))"
    else
      echo "Debian $SUITE root: $ROOT ($([[ -e $ROOT/.tapecoil-debootstrap ]] && echo built || echo not built))"
    fi
    ;;
  *) die "usage: tools/env.sh setup|run CMD...|shell|info" ;;
esac; exit # on the line of esac: bash reads no further, so editing this file mid-run is safe
