#!/usr/bin/env bash
# Every C++ file of the tree is in the style of .clang-format (Debian's
# clang-format; scripts/setup installs it). A file out of style is listed
# with the command that formats it.
#
# Usage: code_format.sh SOURCE_ROOT
set -euo pipefail
root="$1"
format=$(command -v clang-format || true)
if [[ -z "$format" ]]; then
  echo "clang-format is needed (Debian package clang-format; scripts/setup installs it)" >&2
  exit 2
fi
cd "$root"
mapfile -t files < <(find app bench fem modules planning render scene segmentation tests ui \
                          -type f \( -name '*.cpp' -o -name '*.h' \) | sort)
unformatted=()
for file in "${files[@]}"; do
  if ! "$format" --dry-run --Werror "$file" >/dev/null 2>&1; then
    unformatted+=("$file")
  fi
done
if (( ${#unformatted[@]} )); then
  echo "FAIL: ${#unformatted[@]} of ${#files[@]} C++ files are not in the style of .clang-format:"
  printf '  %s\n' "${unformatted[@]}"
  echo "Format them with: clang-format -i ${unformatted[*]}"
  exit 1
fi
echo "PASS: all ${#files[@]} C++ files are in the style of .clang-format"
