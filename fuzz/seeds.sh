#!/bin/sh
# Builds the seed corpora of the fuzz targets in build/fuzz/seeds/: the
# committed seeds (fuzz/seeds/: the tests' scenes, harvested with
# fuzz/harvest.sh, and hosts files of the man page and tests), the shipped
# scenes, and one encoded frame of every message (protocol_seeds).
cd "$(dirname "$0")/.." || exit 1
B=build/fuzz
rm -rf "$B/seeds"
mkdir -p "$B/seeds/scene" "$B/seeds/hosts" "$B/seeds/protocol" "$B/seeds/checkpoint"
cp fuzz/seeds/scene/* "$B/seeds/scene/"
cp fuzz/seeds/hosts/* "$B/seeds/hosts/"
# Checkpoint payloads (the file without its 24-byte header and 32-byte
# SHA-256) of `radiosity -j 0 -r 8 -s 20 --elements 1 --patch-size 1000
# [--no-subdivide] --checkpoint F scenes/{cornell,room}.obj`.
cp fuzz/seeds/checkpoint/* "$B/seeds/checkpoint/"
for s in scenes/*.obj; do HARVEST=$B/seeds/scene sh fuzz/harvest.sh "$s"; done
"$B/protocol_seeds" scenes/cornell.obj "$B/seeds/protocol"
