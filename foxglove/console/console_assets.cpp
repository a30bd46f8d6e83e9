#include "foxglove/console/console_assets.hpp"

namespace rigctl::foxglove {

// Generated at build time (embed_assets.cmake): every file of www/.
extern const ConsoleAsset kConsoleAssets[];
extern const std::size_t kConsoleAssetCount;

const ConsoleAsset* find_console_asset(const std::string& path) {
  const std::string wanted = path == "/" ? "/index.html" : path;
  for (std::size_t i = 0; i < kConsoleAssetCount; ++i) {
    if (kConsoleAssets[i].path == wanted) return &kConsoleAssets[i];
  }
  return nullptr;
}

HttpResponse serve_console_asset(const std::string& path) {
  const ConsoleAsset* a = find_console_asset(path);
  if (a == nullptr) return {404, "text/plain; charset=utf-8", "rigctl console: no page at '" + path + "'\n"};
  return {200, std::string(a->content_type), std::string(a->body)};
}

}  // namespace rigctl::foxglove
