// Keeping freed memory in the process for reuse. portico's processes free
// and take back large buffers over and over (a lease's deposits, crossings
// and messages; a build's scratch; a Result's unpacked segments), and a
// page taken afresh from the system is costly: the kernel zeroes it, and in
// a VM the host may fault it in too (about 12 us a page on the development
// VM, where fresh pages cost 15-25 % of a photon pass's CPU).
#pragma once

#include <cstdint>

namespace portico {

// Lets up to `keptFreeBytes` of free memory stay at the heap's top (glibc's
// trim threshold) and serves blocks up to 32 MiB, the most glibc allows,
// from the heap rather than from fresh mappings.
void keepFreedMemory(uint64_t keptFreeBytes);

}  // namespace portico
