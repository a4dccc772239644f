// The validation pass of `portico scene info`: checks a scene store for
// what SceneStore::open does not (it reads the catalogue only): portals on
// their cells' boundaries, lights and every camera inside their cells, and every
// cell file readable and agreeing with the catalogue.
#pragma once

#include <string>
#include <vector>

#include "common/scene/store/scene_store.h"

namespace portico {

// Every problem found, one line each naming the portal, light, camera, cell
// or cell file and what is wrong; empty for a valid store. Reads every cell
// file (linear in the store's size; portals are indexed by cell).
std::vector<std::string> validateSceneStore(const SceneStore& store);

}  // namespace portico
