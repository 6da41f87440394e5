// dashboard.h — the web dashboard's files (web/src and its chart library, uPlot), embedded in
// the binary at build time by web/tools/embed_web.py. api/src/routes/static_files.cpp serves them:
// "/" and "/jobs/{id}" get the page, "/assets/NAME" the scripts and styles.
#pragma once

#include <string_view>
#include <vector>

namespace manipid::api {

struct DashboardAsset {
  std::string_view path;          ///< "/" or "/assets/NAME"
  std::string_view content_type;
  std::string_view body;
};

const std::vector<DashboardAsset>& dashboard_assets();
/// False when the build found no chart library (npm never ran): "/" then explains how to get it.
bool dashboard_complete();

}  // namespace manipid::api
