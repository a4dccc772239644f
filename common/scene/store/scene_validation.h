// The validation pass of `portico scene info`: checks a scene store for
// what SceneStore::open does not (it reads the catalogue only): portals on
// their cells' boundaries, lights and every camera inside their cells, and every
// cell file readable and agreeing with the catalogue.
#pragma once

#include <string>
#include <vector>

#include "common/scene/store/scene_store.h"

namespace portico {

// How cell files are checked: read through CellGeometry and compared with
// the catalogue (linear in the store's bytes: minutes for the 101-floor
// tower's 25 GB), or only there at the size the catalogue gives (a stat
// each: the summary after generate and import, which just wrote them).
enum class CellFileCheck { Read, Size };

// Every problem found, one line each naming the portal, light, camera, cell
// or cell file and what is wrong; empty for a valid store. Portals are
// indexed by cell: linear in the catalogue.
std::vector<std::string> validateSceneStore(const SceneStore& store, CellFileCheck check = CellFileCheck::Read);

}  // namespace portico
