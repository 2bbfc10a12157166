#!/bin/sh
# Exit 0 when $FUZZ_CXX (default clang++) can build a libFuzzer target
# with ASan and UBSan; else says what is missing on stdout, exit 1.
cxx=${FUZZ_CXX:-clang++}
command -v "$cxx" >/dev/null 2>&1 || { echo "no $cxx (Debian: apt-get install clang)"; exit 1; }
dir=$(mktemp -d) || exit 1
trap 'rm -rf "$dir"' EXIT
echo 'extern "C" int LLVMFuzzerTestOneInput(const unsigned char*, unsigned long) { return 0; }' >"$dir/t.cpp"
"$cxx" -fsanitize=fuzzer,address,undefined -o "$dir/t" "$dir/t.cpp" >/dev/null 2>&1 ||
  { echo "$cxx cannot link -fsanitize=fuzzer (Debian: apt-get install libclang-rt-dev)"; exit 1; }
exit 0
