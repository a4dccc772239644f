#!/usr/bin/env bash
# Downloads the IFC corpus's larger models, and those whose licence (GPL-3.0,
# opensourceBIM/TestFiles) keeps them out of the repository, into DIR at fixed
# commits (tests/scenes/ifc/corpus/README.md), for the corpus table of
# docs/ifc-corpus.md:
#   python/portico_ifc/tools/fetch_corpus.sh DIR
set -euo pipefail
dir="${1:?usage: fetch_corpus.sh DIR}"
mkdir -p "$dir"
web_ifc=https://raw.githubusercontent.com/ThatOpen/engine_web-ifc/233e3aa7118d7364606dcb171206a89b3ed62657
bimserver=https://raw.githubusercontent.com/opensourceBIM/TestFiles/2fdf94854a7fba814a17604ed65f543f125cd265/TestData/data
fetch() {   # url file
  [ -s "$dir/$2" ] && return 0
  curl -fsSL --retry 3 -o "$dir/$2.part" "$1" && mv "$dir/$2.part" "$dir/$2"
  echo "$dir/$2"
}
fetch "$web_ifc/tests/ifcfiles/public/Office_A_20110811.ifc" Office_A_20110811.ifc
fetch "$web_ifc/tests/ifcfiles/public/ISSUE_005_haus.ifc" ISSUE_005_haus.ifc
fetch "$web_ifc/tests/ifcfiles/public/ISSUE_021_Mini%20Project.ifc" "ISSUE_021_Mini Project.ifc"
fetch "$bimserver/AC11-Institute-Var-2-IFC.ifc" AC11-Institute-Var-2-IFC.ifc
fetch "$bimserver/AC90R1-Jasmin-Sun-105-2x3.ifc" AC90R1-Jasmin-Sun-105-2x3.ifc
fetch "$bimserver/AC90R1-niedriha-V2-2x3.ifc" AC90R1-niedriha-V2-2x3.ifc
fetch "$bimserver/ADT-FZK-Haus-2005-2006.ifc" ADT-FZK-Haus-2005-2006.ifc
fetch "$bimserver/Jesse.1.ifc" Revit2013-Jesse.1.ifc
fetch "$bimserver/revit_quantities.ifc" Revit2008-quantities.ifc
fetch "$bimserver/example.ifc" IfcEngine-example.ifc
fetch "$bimserver/japanesechars/revit2013_unicode.ifc" Revit2013-unicode.ifc
fetch "$bimserver/japanesechars/ac16_unicode.ifc" AC16-unicode.ifc
