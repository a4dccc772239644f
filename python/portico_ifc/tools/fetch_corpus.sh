#!/usr/bin/env bash
# Downloads the IFC corpus's larger models (tests/scenes/ifc/corpus/README.md)
# into DIR, at fixed commits, for the corpus table of docs/ifc-corpus.md:
#   python/portico_ifc/tools/fetch_corpus.sh DIR
set -euo pipefail
dir="${1:?usage: fetch_corpus.sh DIR}"
mkdir -p "$dir"
web_ifc=https://raw.githubusercontent.com/ThatOpen/engine_web-ifc/233e3aa7118d7364606dcb171206a89b3ed62657
fetch() {   # url file
  [ -s "$dir/$2" ] && return 0
  curl -fsSL --retry 3 -o "$dir/$2.part" "$1" && mv "$dir/$2.part" "$dir/$2"
  echo "$dir/$2"
}
fetch "$web_ifc/tests/ifcfiles/public/Office_A_20110811.ifc" Office_A_20110811.ifc
fetch "$web_ifc/tests/ifcfiles/public/ISSUE_005_haus.ifc" ISSUE_005_haus.ifc
fetch "$web_ifc/tests/ifcfiles/public/ISSUE_021_Mini%20Project.ifc" "ISSUE_021_Mini Project.ifc"
