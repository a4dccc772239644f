// Finds an entry of portico_image_formats.so, the OpenImageIO module beside
// the running program, loading the module with dlopen on first use. A
// process that never asks for one never loads OpenImageIO.
#pragma once

namespace portico {

// The entry point `name`; throws std::runtime_error saying why it cannot be
// had (the module is missing or lacks it).
void* imageFormatsEntry(const char* name);

}  // namespace portico
