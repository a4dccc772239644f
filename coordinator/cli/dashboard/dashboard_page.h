// The dashboard's page (dashboard_page.html, embedded at configure time:
// the program serves it without reading any file). "{{TOKEN}}" in it is
// replaced by the token as it is served.
#pragma once

#include <string_view>

namespace portico::cli {

extern const std::string_view kDashboardPage;

}  // namespace portico::cli
