#!/usr/bin/env bash
# Fails, naming each, where a function of plydem's own sources is longer than the limit (120 lines:
# issue 31, "A house that stays small as it grows"; generated code lives in the build tree and is
# not read). Lambdas count with the function that holds them. Needs Universal Ctags (Debian
# universal-ctags, scripts/setup); without it the test reports itself skipped (exit 77).
#   tests/check_function_length.sh SOURCE_ROOT [LIMIT]
set -euo pipefail
root=${1:?usage: check_function_length.sh SOURCE_ROOT [LIMIT]}
limit=${2:-120}
if ! ctags --version 2> /dev/null | grep -q "Universal Ctags"; then
  echo "skipped: Universal Ctags (Debian universal-ctags) is not installed"
  exit 77
fi
cd "$root"
folders=(core contacts solvers packings strategies experiments python bench examples tests)
long=$(ctags -R --languages=C++ --map-C++=+.cu --kinds-C++=f --fields=+ne -x \
         --_xformat="%{end} %{line} %{input} %{name}" "${folders[@]}" |
       awk -v limit="$limit" '$1 != "-" { n = $1 - $2 + 1; if (n > limit) print n, $3 ":" $2, $4 }' |
       sort -rn)
if [ -n "$long" ]; then
  echo "functions longer than $limit lines (lines, where, name):"
  echo "$long"
  exit 1
fi
count=$(ctags -R --languages=C++ --map-C++=+.cu --kinds-C++=f -x --_xformat="%{name}" "${folders[@]}" | wc -l)
echo "$count functions, none longer than $limit lines"
