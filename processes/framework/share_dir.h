#pragma once
// Where lanemap's shipped files are: config/, models/, data/ (and the viewer's page).
//
// In order: $LANEMAP_DATA_DIR if set; <folder of the running binary>/../share/lanemap if it holds
// config/ (an installation: `cmake --install` or the Debian package, /usr/bin -> /usr/share/lanemap);
// the source tree the binary was built from (a build folder), if it is still there.
#include <filesystem>
#include <string>

namespace lanemap {

// The folder; throws std::runtime_error naming what was tried when none exists.
std::filesystem::path shareDir();

// The folder of the running program (/proc/self/exe); empty when it cannot be read.
std::filesystem::path executableDir();

// shareDir() / relative, as a string (e.g. shareFile("config/vehicle.yaml")).
std::string shareFile(const std::string& relative);

// A file a user or a config names: as given when absolute or when it exists from the current
// folder, else the same relative path under shareDir() when that exists, else as given (so the
// error that follows names what the user wrote). Throws as shareDir() when it has to look there
// and finds no shipped files.
std::string resolveShippedFile(const std::string& path);

}  // namespace lanemap
