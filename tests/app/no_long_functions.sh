#!/usr/bin/env bash
# No function longer than 120 lines in the libraries and modules (fem/,
# segmentation/, planning/, render/, modules/; tests excepted): a long function is a
# pipeline whose steps want names (the deal.II run() habit). Lambdas count as
# functions. Function extents come from universal-ctags.
#
# Usage: no_long_functions.sh SOURCE_ROOT
set -euo pipefail
root="$1"
limit=120
ctags=$(command -v ctags-universal || command -v ctags || true)
if [[ -z "$ctags" ]] || ! "$ctags" --version 2>/dev/null | grep -q "Universal Ctags"; then
  echo "universal-ctags is needed (Debian package universal-ctags; scripts/setup installs it)" >&2
  exit 2
fi
cd "$root"
long=$("$ctags" -R --languages=C++ --kinds-C++=f --fields=+ne -x --_xformat="%N|%F|%n|%e" \
         fem segmentation planning render modules |
       awk -F'|' -v limit="$limit" '$4 != "" && $4 - $3 + 1 > limit { printf "%5d lines  %s:%s  %s\n", $4 - $3 + 1, $2, $3, $1 }' |
       sort -rn)
count=$("$ctags" -R --languages=C++ --kinds-C++=f --fields=+ne -x --_xformat="%N" fem segmentation planning render modules | wc -l)
if [[ -n "$long" ]]; then
  echo "FAIL: functions longer than $limit lines (split them into named steps):"
  echo "$long"
  exit 1
fi
echo "PASS: none of the $count functions in fem/, segmentation/, planning/, render/ and modules/ is longer than $limit lines"
