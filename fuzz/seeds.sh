#!/bin/sh
# Builds the seed corpora of the fuzz targets in build/fuzz/seeds/: the
# committed seeds (fuzz/seeds/: the tests' scenes, harvested with
# fuzz/harvest.sh, and hosts files of the man page and tests), the shipped
# scenes, and one encoded frame of every message (protocol_seeds).
cd "$(dirname "$0")/.." || exit 1
B=build/fuzz
rm -rf "$B/seeds"
mkdir -p "$B/seeds/scene" "$B/seeds/hosts" "$B/seeds/protocol"
cp fuzz/seeds/scene/* "$B/seeds/scene/"
cp fuzz/seeds/hosts/* "$B/seeds/hosts/"
for s in scenes/*.obj; do HARVEST=$B/seeds/scene sh fuzz/harvest.sh "$s"; done
"$B/protocol_seeds" scenes/cornell.obj "$B/seeds/protocol"
