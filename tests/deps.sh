#!/bin/sh
# Installs the Debian packages radiosity needs to build and test, only when
# one is missing. Run by `make check`, `make demo` and `make bench`.
pkgs="g++ make pkg-config libglm-dev libstb-dev libgtest-dev groff-base libssh-dev openssh-client openssh-server"
missing=""
for p in $pkgs; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing="$missing $p"
done
[ -z "$missing" ] && exit 0
echo "radiosity: installing missing Debian packages:$missing"
if [ "$(id -u)" != 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO=sudo; else
    echo "radiosity: need root (or sudo) to install:$missing" >&2; exit 1; fi
fi
$SUDO apt-get update -q && $SUDO apt-get install -y -q $missing || {
  echo "radiosity: could not install:$missing (apt-get failed; install them by hand)" >&2
  exit 1
}
