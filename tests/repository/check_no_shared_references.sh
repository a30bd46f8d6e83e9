#!/usr/bin/env bash
# The repository must stand on its own. Its documents once lived in a folder
# beside it that a user's clone does not have; what users need is now in
# docs/ (run-files.md, rig-models.md, diagnosis.md) and tests/data/. This
# check fails, naming file and line, when anything points into that folder
# again or names one of its old documents.
#
# Usage: check_no_shared_references.sh [SOURCE_DIR]   (default: .)
# Exit 0: clean; 1: references found (listed on stdout); 2: cannot search.
#
# Searched: with git, the tracked files and the untracked ones that are not
# ignored (what the next commit could contain; build trees are ignored);
# without git (a source tarball), every text file except .git, build*/ and
# runs/. Binary files are skipped.
#
# The pattern is assembled from parts so that this script does not match
# itself: the folder as a path component (start of text or a character that
# cannot be part of a name before it, a slash after it), or the old
# documents' file names.
set -u

root=${1:-.}
cd "$root" 2>/dev/null || { echo "check_no_shared_references: cannot enter '$root'" >&2; exit 2; }

folder="shared"
old_docs="rig-parameters|diagnosis-notes|measured-data|platform-notes"
pattern="(^|[^A-Za-z0-9_])${folder}/|(${old_docs})[.]md"

hits=""
searched=""
if command -v git >/dev/null 2>&1 && git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  hits=$(git grep -I -n -E --untracked -e "$pattern" -- . 2>/dev/null)
  rc=$?
  if [ "$rc" -le 1 ]; then searched="git grep"; fi
fi
if [ -z "$searched" ]; then
  hits=$(grep -rIn -E --exclude-dir=.git --exclude-dir='build*' --exclude-dir=runs -e "$pattern" . 2>/dev/null)
  rc=$?
  if [ "$rc" -gt 1 ]; then
    echo "check_no_shared_references: grep failed in $(pwd)" >&2
    exit 2
  fi
  searched="grep -r"
fi

if [ -n "$hits" ]; then
  echo "References to the ${folder}/ folder or its old documents (a user's clone has neither;"
  echo "point them at docs/run-files.md, docs/rig-models.md, docs/diagnosis.md or tests/data/):"
  printf '%s\n' "$hits" | head -n 100
  n=$(printf '%s\n' "$hits" | wc -l)
  [ "$n" -gt 100 ] && echo "... and $((n - 100)) more lines"
  echo "Files:"
  printf '%s\n' "$hits" | cut -d: -f1 | sort -u | sed 's/^/  /'
  exit 1
fi
echo "No references to the ${folder}/ folder ($searched in $(pwd))."
exit 0
