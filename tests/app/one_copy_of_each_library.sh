#!/usr/bin/env bash
# One copy of each CAPS library in a process: no symbol of namespace caps is
# defined (strong, global) in more than one binary of the build, when one of
# them is a shared library or a plugin. A static library linked into two
# plugins, or the same function defined in two libraries, shows here as a
# symbol defined twice.
#
# Usage: one_copy_of_each_library.sh LIST
#   LIST: a file naming the build's binaries, one per line (libraries,
#   plugins, executables), as CMake generates it.
set -euo pipefail
list="$1"
[[ -s "$list" ]] || { echo "no binaries listed in $list: build first" >&2; exit 2; }

pairs=$(mktemp)
trap 'rm -f "$pairs"' EXIT
while IFS= read -r binary; do
  [[ -n "$binary" ]] || continue
  if [[ ! -f "$binary" ]]; then
    echo "missing binary $binary: build first" >&2
    exit 2
  fi
  # Strong global definitions (text, data, bss, read-only data). Weak and
  # unique symbols (inline functions, templates, vtables of classes without
  # a key function) are folded by the dynamic linker, and a plugin's hidden
  # copies of inline functions are local to it; names with internal linkage
  # (anonymous namespaces, "L" statics) are not shared code. A static library
  # linked with hidden visibility would leave only local copies: the
  # configure step refuses static CAPS libraries for that reason
  # (cmake/OneCopyOfEachLibrary.cmake).
  nm --defined-only "$binary" |
    awk -v file="$binary" '$2 ~ /^[TDBR]$/ && $3 ~ /^_Z(T[VIST])?NK?4caps/ &&
                           $3 !~ /_GLOBAL__N|L[0-9]/ { print $3, file }'
done < "$list" | sort -u > "$pairs"

echo "$(wc -l < "$pairs") definitions of namespace caps in $(grep -c . "$list") binaries"
# Symbols defined in more than one binary, where one of them is a library or
# a plugin (test programs may share a helper source among themselves).
duplicates=$(awk '
  { files[$1] = files[$1] " " $2; count[$1]++;
    if ($2 ~ /\.so$/) shared[$1] = 1 }
  END { for (s in count) if (count[s] > 1 && shared[s]) print s, files[s] }' "$pairs" | sort)
if [[ -n "$duplicates" ]]; then
  echo "FAIL: $(echo "$duplicates" | wc -l) symbols are defined in more than one binary:"
  echo "$duplicates" | head -20 | while read -r symbol files; do
    echo "  $(echo "$symbol" | c++filt) in:$(for f in $files; do printf ' %s' "$(basename "$f")"; done)"
  done
  echo "Each library must be shared and linked, not compiled or linked statically into several binaries."
  exit 1
fi
echo "PASS: every library's code is in exactly one binary"
