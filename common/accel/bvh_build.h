// Which binning loop `bvh`'s builder (bvh_build.cpp) uses: with AVX where
// the processor has it (the default), else SSE. Both give the same bins, so
// the same tree bit for bit; the switch lets tests compare them.
#pragma once

namespace portico {

// Whether builds bin with AVX (true only where the processor has it).
bool bvhAvxBinningInUse();

// Bins with AVX (where the processor has it) or with SSE, for the builds
// that start afterwards on any thread.
void useBvhAvxBinning(bool use);

}  // namespace portico
