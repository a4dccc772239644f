// The names of the files a scene store is made of, as the coordinator serves
// them and a --cache-dir worker writes them: "scene.db",
// "cells/<digits>.cell" and "textures/<digits>.tif", nothing else. A name
// from the network is checked against these before it is opened or
// written: no "..", no absolute path, no other folder.
#pragma once

#include <string>

namespace portico {

bool isServableStorePath(const std::string& path);

class SceneStore;
// Throws naming the first cell or texture file of `store` that is there but
// not a regular file (a FIFO, a device, a folder): opening one could block
// its reader for good. A stat each: linear in the cells, not their bytes.
void requireRegularStoreFiles(const SceneStore& store);

}  // namespace portico
