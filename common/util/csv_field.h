// CSV cells, for the bench commands' output and the analysis results.
#pragma once

#include <string>

namespace portico {

// The text as one CSV cell: quoted (RFC 4180, quotes doubled) when it holds a
// comma, a quote or a newline, as accelerator specs with parameters
// ("hgrid:res=64,max=8") do; unchanged otherwise.
std::string csvField(const std::string& text);

}  // namespace portico
