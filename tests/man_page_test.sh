#!/usr/bin/env bash
# Checks man/ssgi.1: every long option of the option table and the getopt_long tables of cli/*.cpp is documented
# (as \-\-name or --name), and the page renders with groff without a single warning.
# Usage: man_page_test.sh [PROJECT_SOURCE_DIR]   (default: the repository this script is in)
set -euo pipefail

root=${1:-"$(cd "$(dirname "$0")/.." && pwd)"}
page="$root/man/ssgi.1"
fail=0

if [ ! -s "$page" ]; then
  echo "man_page_test: $page is missing or empty" >&2
  exit 1
fi

# Long options: the option table's entries ({kMaxSteps, "max-steps", ...} in
# cli/option_table.cpp) and getopt_long tables ({"max-steps", required_argument, ...}).
mapfile -t options < <( {
  grep -ohE '\{"[A-Za-z0-9][A-Za-z0-9-]*",[[:space:]]*(no|required|optional)_argument' \
    "$root"/cli/*.cpp | sed -E 's/^\{"([^"]+)".*/\1/'
  grep -ohE "^[[:space:]]*\{(k[A-Za-z]+|'[a-z]'), \"[a-z0-9-]+\"," "$root"/cli/option_table.cpp |
    sed -E 's/.*"([^"]+)",$/\1/'
} | sort -u)
if [ ${#options[@]} -eq 0 ]; then
  echo "man_page_test: found no getopt_long options in $root/cli/*.cpp" >&2
  exit 1
fi
for name in "${options[@]}"; do
  # --max-steps as roff writes it (\-\-max\-steps) or plainly, and not as the start of a longer
  # option (--env must not be found in --env-up).
  hyphen='(\\-|-)'
  body=$(printf '%s' "$name" | sed 's/-/(\\\\-|-)/g')
  pattern="${hyphen}${hyphen}${body}(\$|[^A-Za-z0-9\\-]|\\\\[^-])"
  if ! grep -qE -e "$pattern" "$page"; then
    echo "man_page_test: option --$name (cli/*.cpp) is not documented in man/ssgi.1" >&2
    fail=1
  fi
done

# Render with every warning enabled; any output on stderr is a failure.
if ! command -v groff >/dev/null; then
  echo "man_page_test: groff not found (install groff-base)" >&2
  exit 1
fi
warnings=$(LC_ALL=C.UTF-8 groff -man -Tutf8 -ww -z "$page" 2>&1 >/dev/null) || {
  echo "man_page_test: groff failed on $page" >&2
  fail=1
}
if [ -n "$warnings" ]; then
  echo "man_page_test: groff warnings in $page:" >&2
  echo "$warnings" >&2
  fail=1
fi

if [ "$fail" -eq 0 ]; then
  echo "man_page_test: ${#options[@]} long options documented; page renders without warnings"
fi
exit "$fail"
