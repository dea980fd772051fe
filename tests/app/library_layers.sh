#!/usr/bin/env bash
# The libraries below the modules keep to their layer: fem/, segmentation/,
# planning/ and render/ include nothing of the scene, the modules, the app or
# the shared widgets (ui/), no Qt Widgets header, and their shared objects do
# not link Qt5Widgets. Each includes only the libraries below it:
#   fem          fem
#   segmentation segmentation
#   planning     planning fem segmentation
#   render       render segmentation
#
# Usage: library_layers.sh SOURCE_ROOT LIBRARY_DIR QTWIDGETS_INCLUDE_DIR
set -euo pipefail
root="$1"
libdir="$2"
widgets="$3"
[[ -d "$widgets" ]] || { echo "no Qt Widgets include folder at $widgets" >&2; exit 2; }
declare -A allowed=(
  [fem]="fem"
  [segmentation]="segmentation"
  [planning]="planning fem segmentation"
  [render]="render segmentation"
)
problems=""
for library in fem segmentation planning render; do
  # Our own headers: "folder/File.h".
  while IFS=: read -r file line text; do
    folder=$(sed -E 's/.*#include "([^/"]+)\/.*/\1/' <<<"$text")
    if [[ " ${allowed[$library]} " != *" $folder "* ]]; then
      problems+="  $file:$line includes $folder/ (not below $library/)"$'\n'
    fi
  done < <(cd "$root" && grep -Hn '^[[:space:]]*#[[:space:]]*include[[:space:]]*"[^/"]*/' $library/*.h $library/*.cpp || true)
  # Qt Widgets headers: <QWidget>, <QtWidgets/...>, or any name QtWidgets ships.
  while IFS=: read -r file line text; do
    header=$(sed -E 's/.*#[[:space:]]*include[[:space:]]*<([^>]+)>.*/\1/' <<<"$text")
    if [[ "$header" == QtWidgets/* || -e "$widgets/$header" ]]; then
      problems+="  $file:$line includes the Qt Widgets header <$header>"$'\n'
    fi
  done < <(cd "$root" && grep -Hn '^[[:space:]]*#[[:space:]]*include[[:space:]]*<Q' $library/*.h $library/*.cpp || true)
  so="$libdir/libcaps_$library.so"
  [[ -f "$so" ]] || { echo "no $so: build the project first" >&2; exit 2; }
  if readelf -d "$so" | grep -q 'NEEDED.*libQt5Widgets'; then
    problems+="  $so links Qt5Widgets"$'\n'
  fi
done
if [[ -n "$problems" ]]; then
  echo "FAIL: a library below the modules reaches above its layer:"
  printf '%s' "$problems"
  exit 1
fi
echo "PASS: fem/, segmentation/, planning/ and render/ keep to their layers and build without Qt Widgets"
