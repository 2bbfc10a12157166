#!/bin/sh
# Installs the Debian packages radiosity needs to build and test, only when
# one is missing. Run by `make check`, `make demo` and `make bench`.
pkgs="g++ make pkg-config libglm-dev libstb-dev libtinyexr-dev libgtest-dev groff-base libssh-dev libssl-dev openssh-client openssh-server libcpp-httplib-dev liblz4-dev libzstd-dev"
missing=""
for p in $pkgs; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing="$missing $p"
done
# The fuzz targets (make fuzz; make check runs them briefly) need clang and
# libFuzzer, tests/view.sh a browser (headless Chromium), and
# tests/launchers.sh the cluster launchers it starts workers with (Open
# MPI's mpirun; Slurm's daemons and srun, authenticated by munge), and
# tests/throttle.sh a rate limiter for a worker's link (pv); without them
# make check skips those tests, so a failure to install these is only a
# warning.
optional_pkgs="clang libclang-rt-dev chromium openmpi-bin slurm-wlm munge pv"
optional_missing=""
for p in $optional_pkgs; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || optional_missing="$optional_missing $p"
done
[ -z "$missing" ] && [ -z "$optional_missing" ] && exit 0
echo "radiosity: installing missing Debian packages:$missing$optional_missing"
SUDO=""
if [ "$(id -u)" != 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO=sudo; elif [ -n "$missing" ]; then
    echo "radiosity: need root (or sudo) to install:$missing" >&2; exit 1; else
    echo "radiosity: warning: need root (or sudo) to install:$optional_missing; the fuzz, view, launcher and throttle tests will be skipped" >&2; exit 0; fi
fi
$SUDO apt-get update -q || { [ -z "$missing" ] || {
  echo "radiosity: could not install:$missing (apt-get update failed; install them by hand)" >&2
  exit 1; }; }
if [ -n "$missing" ]; then
  $SUDO apt-get install -y -q $missing || {
    echo "radiosity: could not install:$missing (apt-get failed; install them by hand)" >&2
    exit 1
  }
fi
# All at once, and where that fails one by one, so that one package the
# archive lacks (chromium on some mirrors) does not keep the others out.
if [ -n "$optional_missing" ] && ! $SUDO apt-get install -y -q $optional_missing; then
  for p in $optional_missing; do
    $SUDO apt-get install -y -q "$p" ||
      echo "radiosity: warning: could not install $p; the tests that need it will be skipped" >&2
  done
fi
exit 0
