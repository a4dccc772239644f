#include "common/util/heap_reuse.h"

#include <malloc.h>

#include <algorithm>
#include <climits>

namespace portico {

void keepFreedMemory(uint64_t keptFreeBytes) {
  mallopt(M_TRIM_THRESHOLD, int(std::min<uint64_t>(keptFreeBytes, INT_MAX)));
  mallopt(M_MMAP_THRESHOLD, 32 * 1024 * 1024);
}

}  // namespace portico
