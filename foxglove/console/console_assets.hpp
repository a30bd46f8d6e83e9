// The console's page (foxglove/console/www: HTML, JavaScript, CSS, no build
// step), compiled into the program by CMake (embed_assets.cmake writes
// console_assets_data.cpp from the files), so the installed binary serves
// it and nothing is fetched from a network at run time.
#pragma once

#include <string>
#include <string_view>

#include "foxglove/server/server.hpp"

namespace rigctl::foxglove {

struct ConsoleAsset {
  std::string_view path;  // "/index.html", "/console.js", ...
  std::string_view content_type;
  std::string_view body;
};

// nullptr for a path that is not one of the page's files ("/" is /index.html).
const ConsoleAsset* find_console_asset(const std::string& path);

// The server's HTTP handler: the asset, or 404 naming the path.
HttpResponse serve_console_asset(const std::string& path);

}  // namespace rigctl::foxglove
