// An output path (an image, or an analysis's CSV) checked before a job is accepted rather than after
// its render: a known image extension (or .csv), not a directory, in a directory
// that exists and that the checking process may write. Nothing is created:
// the client checks as the user who asks, the coordinator as itself, and
// neither makes directories on another user's behalf.
#pragma once

#include <string>

namespace portico {

// What the output is: an image, or a lighting analysis's results (.csv).
enum class OutputKind { Image, AnalysisCsv };

// Throws std::invalid_argument with a one-line message naming the path and
// the problem.
void checkOutputPath(const std::string& path, OutputKind kind = OutputKind::Image);

}  // namespace portico
