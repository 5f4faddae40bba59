#!/bin/sh
# The man page and bash completion of the tool.
# usage: cli_man_completion.sh NORMALFLOW MANPAGE COMPLETION
set -u
bin=$1 man=$2 completion=$3
fail() { echo "$*"; exit 1; }
# the man page: renders without a warning, has every subcommand (as the tool lists them) and their flags
[ -f "$man" ] || fail "no man page at $man"
warnings=$(groff -man -Tutf8 -ww -z "$man" 2>&1) || fail "groff failed: $warnings"
[ -z "$warnings" ] || fail "groff warnings: $warnings"
subs=$("$bin" --help | sed -n '/^Subcommands:/,$ s/^  \([a-z][a-z]*\)  .*/\1/p')
[ "$(echo "$subs" | wc -l)" -ge 10 ] || fail "too few subcommands in --help: $subs"
for s in $subs; do grep -q "^\.SS $s\$" "$man" || fail "the man page has no section for $s"; done
# --help's flags and --help-all's
for f in target-faces connectivity config jobs sigma-range no-repair; do grep -q -- "-$f" "$man" || fail "the man page lacks --$f"; done
# completion: subcommands, flags, a flag's choices, file names
complete() { bash -c ". '$completion'; COMP_WORDS=($1); COMP_CWORD=$2; _normalflow; echo \"\${COMPREPLY[*]}\""; }
[ "$(complete "$bin sm" 1)" = "smooth" ] || fail "sm -> $(complete "$bin sm" 1)"
[ "$(complete "$bin smooth --target-f" 2)" = "--target-faces" ] || fail "--target-f -> $(complete "$bin smooth --target-f" 2)"
[ "$(complete "$bin smooth --connectivity ''" 3)" = "auto keep remesh" ] || fail "--connectivity -> $(complete "$bin smooth --connectivity ''" 3)"
[ "$(complete "$bin smooth x.ply --mode b" 4)" = "bilateral" ] || fail "--mode b -> $(complete "$bin smooth x.ply --mode b" 4)"
[ "$(complete "$bin smooth --iterations ''" 3)" = "auto" ] || fail "--iterations offered $(complete "$bin smooth --iterations ''" 3)"
[ -z "$(complete "$bin smooth --shell ''" 3)" ] || fail "--shell offered $(complete "$bin smooth --shell ''" 3)"
[ "$(complete "$bin smooth --sigma-r" 2)" = "--sigma-range" ] || fail "--sigma-r -> $(complete "$bin smooth --sigma-r" 2)"
[ "$(complete "$bin batch --jo" 2)" = "--jobs" ] || fail "batch --jo -> $(complete "$bin batch --jo" 2)"
dir=$(mktemp -d) && touch "$dir/part.ply" && [ "$(complete "$bin smooth $dir/pa" 2)" = "$dir/part.ply" ] || fail "files"
rm -rf "$dir"
exit 0
