#!/usr/bin/env bash
# Checks the man pages in man/ (ssgi(1), ssgi-<subcommand>(1), the ssgi-*(7) topics):
# - every long option that `ssgi <subcommand> --help` lists has an entry (a .TP tag) in
#   man/ssgi-<subcommand>.1, as \-\-name or --name (compare's one-dash options as \-name);
# - every long option of the option table and the getopt_long tables of cli/*.cpp and
#   lib/src/options/*.cpp has an entry in at least one page;
# - every page renders with groff without a single warning, is listed in ssgi(1)'s SEE ALSO,
#   and is installed by the top-level CMakeLists.txt into man1 or man7 as its section says.
# Each failure is one line naming the page and what is missing.
# Usage: man_page_test.sh PROJECT_SOURCE_DIR SSGI_BINARY
set -euo pipefail

if [ $# -ne 2 ]; then
  echo "usage: man_page_test.sh PROJECT_SOURCE_DIR SSGI_BINARY" >&2
  exit 2
fi
root=$1
ssgi=$2
subcommands=(run info reference compare sweep preview)
fail=0

if [ ! -x "$ssgi" ]; then
  echo "man_page_test: $ssgi is not an executable" >&2
  exit 1
fi
if ! command -v groff >/dev/null; then
  echo "man_page_test: groff not found (install groff-base)" >&2
  exit 1
fi

shopt -s nullglob
pages=("$root"/man/*.[1-9])
if [ ${#pages[@]} -eq 0 ]; then
  echo "man_page_test: no man pages in $root/man" >&2
  exit 1
fi

# The tags of a page's entries: the line after each .TP.
entry_tags() {
  awk 'tp { print; tp = 0 } /^\.TP/ { tp = 1 }' "$@"
}

# Whether an option (with its dashes, e.g. --max-steps or -fail) is among the tags on stdin:
# written as roff writes it (\-\-max\-steps) or plainly, and not as the start of a longer option
# (--env must not be found in --env-up).
has_option() {
  local body dashes pattern
  dashes=${1%%[!-]*}
  body=$(printf '%s' "${1#"$dashes"}" | sed 's/-/(\\\\-|-)/g')
  pattern="$(printf '%s' "$dashes" | sed 's/-/(\\\\-|-)/g')${body}(\$|[^A-Za-z0-9\\-]|\\\\[^-])"
  grep -qE -e "$pattern"
}

# 1. Each subcommand's page has an entry for every long option its --help lists (lines that
# start with two spaces and a dash: "  -o, --output PATTERN", "  -warn X").
for sub in "${subcommands[@]}"; do
  page="$root/man/ssgi-$sub.1"
  if [ ! -s "$page" ]; then
    echo "man_page_test: man/ssgi-$sub.1 is missing or empty" >&2
    fail=1
    continue
  fi
  help=$("$ssgi" "$sub" --help) || {
    echo "man_page_test: '$ssgi $sub --help' failed" >&2
    fail=1
    continue
  }
  mapfile -t options < <(printf '%s\n' "$help" |
    sed -nE 's/^  (-[^ ,]+)(, (--[^ ,]+))?.*/\1\n\3/p' | grep -E '^--?[A-Za-z0-9][A-Za-z0-9-]+$' |
    sort -u)
  if [ ${#options[@]} -eq 0 ]; then
    echo "man_page_test: '$ssgi $sub --help' lists no long options" >&2
    fail=1
    continue
  fi
  tags=$(entry_tags "$page")
  for option in "${options[@]}"; do
    if ! printf '%s\n' "$tags" | has_option "$option"; then
      echo "man_page_test: man/ssgi-$sub.1: no entry for $option (listed by 'ssgi $sub --help')" >&2
      fail=1
    fi
  done
  checked=$((${checked:-0} + ${#options[@]}))
done

# 2. Every long option in the sources has an entry in some page: the option table's entries
# ({kMaxSteps, "max-steps", ...} in lib/src/options/option_table.cpp) and getopt_long tables
# ({"max-steps", required_argument, ...}).
mapfile -t source_options < <( {
  grep -ohE '\{"[A-Za-z0-9][A-Za-z0-9-]*",[[:space:]]*(no|required|optional)_argument' \
    "$root"/cli/*.cpp "$root"/lib/src/options/*.cpp | sed -E 's/^\{"([^"]+)".*/\1/'
  grep -ohE "^[[:space:]]*\{(k[A-Za-z]+|'[a-z]'), \"[a-z0-9-]+\"," \
    "$root"/lib/src/options/option_table.cpp | sed -E 's/.*"([^"]+)",$/\1/'
} | grep -E '^.{2,}$' | sort -u)
if [ ${#source_options[@]} -eq 0 ]; then
  echo "man_page_test: found no long options in $root/cli/*.cpp, $root/lib/src/options/*.cpp" >&2
  fail=1
fi
all_tags=$(entry_tags "${pages[@]}")
for name in "${source_options[@]}"; do
  # compare's idiff options are written with one dash (-fail), the others with two.
  if ! printf '%s\n' "$all_tags" | has_option "-$name"; then
    echo "man_page_test: man/*: no entry for --$name (cli/*.cpp, lib/src/options/*.cpp)" >&2
    fail=1
  fi
done

# 3. Every page renders without warnings, is in ssgi(1)'s SEE ALSO and is installed.
overview="$root/man/ssgi.1"
see_also=$(awk '/^\.SH/ { on = ($0 ~ /^\.SH "?SEE ALSO"?$/); next } on' "$overview" | sed 's/\\-/-/g')
# install(FILES ...) calls of the top-level CMakeLists.txt, one per line.
installs=$(tr '\n' ' ' <"$root/CMakeLists.txt" | grep -oE 'install\(FILES[^)]*\)' || true)
for page in "${pages[@]}"; do
  file=${page##*/}
  name=${file%.*}
  section=${file##*.}
  warnings=$(LC_ALL=C.UTF-8 groff -man -Tutf8 -ww -z "$page" 2>&1 >/dev/null) || {
    echo "man_page_test: man/$file: groff failed" >&2
    fail=1
  }
  if [ -n "$warnings" ]; then
    printf '%s\n' "$warnings" | sed "s|^|man_page_test: man/$file: groff: |" >&2
    fail=1
  fi
  if ! grep -qE "^\.TH $(printf '%s' "$name" | tr a-z A-Z) $section " "$page"; then
    echo "man_page_test: man/$file: its .TH line does not name $name in section $section" >&2
    fail=1
  fi
  if [ "$file" != ssgi.1 ] &&
    ! grep -qE "^\.BR $name \($section\)" <<<"$see_also"; then
    echo "man_page_test: man/$file: not listed in SEE ALSO of man/ssgi.1" >&2
    fail=1
  fi
  # Without -q the last grep reads all its input: under pipefail, a grep -q that stops at its
  # first match can kill the writer with SIGPIPE and fail the pipeline.
  if ! grep -F "man/$file" <<<"$installs" | grep -F "MANDIR}/man$section" >/dev/null; then
    echo "man_page_test: man/$file: not installed to \${CMAKE_INSTALL_MANDIR}/man$section" \
      "by CMakeLists.txt" >&2
    fail=1
  fi
done

# 4. Every ssgi page a page refers to exists.
while IFS=: read -r file ref; do
  target=$(printf '%s' "$ref" | sed -E 's/^\.BR ([^ ]+) \(([0-9])\).*/\1.\2/; s/\\-/-/g')
  if [ ! -f "$root/man/$target" ]; then
    echo "man_page_test: man/${file##*/}: refers to ${target%.*}(${target##*.}), which has no page" >&2
    fail=1
  fi
done < <(grep -oE '^\.BR ssgi(\\?-[a-z]+)? \([0-9]\)' "${pages[@]}")

if [ "$fail" -eq 0 ]; then
  echo "man_page_test: ${#pages[@]} pages render without warnings, are installed and listed;" \
    "${checked} options of ${#subcommands[@]} subcommands and ${#source_options[@]} of cli/*.cpp documented"
fi
exit "$fail"
