#!/bin/bash
# The manual against the program: every long option of --help is
# documented in man/radiosity.1 and every option the man page documents is
# in --help; the sections a user looks for are there; every output file a
# run writes is described; `make install` puts the page where man finds it.
# (The groff lint itself is run by tests/run.sh.)
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"

TOP=$(cd "$(dirname "$0")/.." && pwd)
MAN=$TOP/man/radiosity.1

"$RADIOSITY" --help | grep -o -- '--[a-z][a-z-]*' | sort -u >"$T/help"
# The man page's options: its OPTIONS section's tagged paragraphs (.TP and
# the line after), with roff's \- turned into -.
awk '/^\.SH OPTIONS/ { on = 1; next } /^\.SH/ { on = 0 } on && prev == ".TP" { print } { prev = $0 }' "$MAN" |
  sed 's/\\-/-/g' | grep -o -- '--[a-z][a-z-]*' | sort -u >"$T/man"
[ "$(wc -l <"$T/help")" -ge 30 ] && pass "--help lists $(wc -l <"$T/help") long options" \
  || fail "--help lists only $(wc -l <"$T/help") long options"
missing=$(comm -23 "$T/help" "$T/man" | tr '\n' ' ')
[ -z "$missing" ] && pass "every long option of --help is in the man page's OPTIONS" \
  || fail "in --help, not in the man page's OPTIONS: $missing"
extra=$(comm -13 "$T/help" "$T/man" | tr '\n' ' ')
[ -z "$extra" ] && pass "every option of the man page's OPTIONS is in --help" \
  || fail "in the man page's OPTIONS, not in --help: $extra"

for section in NAME SYNOPSIS DESCRIPTION OPTIONS PROGRESS WORKERS "HOSTS FILE" "REMOTE WORKERS" \
  "CONNECT\\\\-BACK" TROUBLESHOOTING "SCENE FORMAT" "OUTPUT FILES" FILES SECURITY LIMITS "EXIT STATUS" ENVIRONMENT \
  EXAMPLES "SEE ALSO"; do
  grep -q "^\.SH $section\$" "$MAN" && pass "section ${section//\\\\/}" || fail "no section ${section//\\\\/}"
done
# EXIT STATUS lists exactly the statuses of exit_status.h (its values, in
# order), as the header's comment asks.
enum=$(sed -n 's/^ *kExit[A-Za-z]* = \([0-9]*\),.*/\1/p' "$TOP/exit_status.h" | tr '\n' ' ')
page=$(awk '/^\.SH EXIT STATUS/ { on = 1; next } /^\.SH/ { on = 0 } on && prev == ".TP" { print } { prev = $0 }' "$MAN" |
  sed -n 's/^\.B \([0-9]*\)$/\1/p' | tr '\n' ' ')
[ -n "$enum" ] && [ "$enum" = "$page" ] && pass "EXIT STATUS lists exit_status.h's statuses: $enum" \
  || fail "EXIT STATUS lists '$page', exit_status.h has '$enum'"
grep -q '^srun radiosity' "$MAN" && grep -q '^mpirun ' "$MAN" && pass "Slurm and mpirun examples" \
  || fail "Slurm or mpirun example missing"

# Every file a converged run writes is described under OUTPUT FILES.
run_rad "$T/run" -j 0 -r 32 -s 50 "$TOP/scenes/cornell.obj"
files=$(cd "$T/run" && ls | sed 's/frame-[0-9]*\./frame-NN./' | sort -u)
out=$(awk '/^\.SH OUTPUT FILES/ { on = 1; next } /^\.SH/ { on = 0 } on' "$MAN" | sed 's/\\-/-/g')
for f in $files; do
  grep -q -- "$f" <<<"$out" && pass "OUTPUT FILES describes $f" || fail "OUTPUT FILES lacks $f"
done

# make install: PREFIX/share/man/man1, where man -w finds it. Under make
# check this runs inside make: its jobserver and flags are not ours.
unset MAKEFLAGS MFLAGS MAKELEVEL
if make -C "$TOP" -q radiosity 2>/dev/null; then
  make -C "$TOP" --no-print-directory install DESTDIR="$T/root" PREFIX=/usr/local >"$T/install.log" 2>&1
  page=$T/root/usr/local/share/man/man1/radiosity.1
  if cmp -s "$page" "$MAN" && [ -x "$T/root/usr/local/bin/radiosity" ]; then
    pass "make install: bin/radiosity and share/man/man1/radiosity.1 under PREFIX"
  else
    fail "make install: $(tail -3 "$T/install.log")"
  fi
  if command -v man >/dev/null 2>&1; then
    found=$(MANPATH=$T/root/usr/local/share/man man -w radiosity 2>/dev/null)
    [ "$found" = "$page" ] && pass "man -w radiosity finds the installed page" \
      || fail "man -w radiosity (got '$found', want $page)"
  fi
else
  echo "skip: make install check (./radiosity is not up to date; build it first)"
fi

finish
