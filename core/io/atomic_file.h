// Atomic, durable file writing for every writer of lanemap (the map store, the maps, summaries):
// the content goes to `<path>.tmp.<pid>` in the same folder, is flushed to disk (fsync), renamed
// over `path`, and the folder is flushed (fsync) so the rename itself survives a power loss. A
// reader, a crash or a power loss sees either the old complete file or the new complete file,
// never a half-written one. What a writer killed mid-write leaves is a `.tmp.<pid>` file that no
// reader takes (removeStaleTemporaries clears them).
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

namespace lanemap::io {

class IoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Writes `content` to `path` atomically (temporary file in the same folder, fsync, rename, fsync
// of the folder). The folder must exist. Throws IoError naming the path and the reason (e.g. "No
// space left on device", "Read-only file system") on any failure; the temporary file is removed
// then and `path` is left as it was.
void writeFileAtomically(const std::string& path, std::string_view content);

// Binary variant for encoded images and the like.
void writeFileAtomically(const std::string& path, const void* data, size_t size);

// Creates `dir` and its missing parents; each folder it creates is made durable (fsync of its
// parent). Throws IoError naming the folder on failure.
void createDirectories(const std::string& dir);

// Removes `path` if it exists and flushes its folder, so the removal survives a power loss and is
// ordered after what was written before it. Returns whether it existed; throws IoError when it
// exists and cannot be removed.
bool removeFileDurably(const std::string& path);

// Renames `from` over `to` (same folder) and flushes the folder. Throws IoError naming both.
void renameFileDurably(const std::string& from, const std::string& to);

// Removes the temporaries `<name>.tmp.<pid>` in `dir` whose writer (pid) is no longer running
// (what a writer killed mid-write leaves). Returns how many it removed.
int removeStaleTemporaries(const std::string& dir);

// Fault injection for tests: called at each step of the functions above with the step and the
// file's final path (for kFolderSynced: the folder). A test makes a child process _exit() or
// SIGKILL itself in a hook to crash it between two steps; nullptr (the default) turns it off.
enum class WriteStep {
  kTemporaryCreated,  // the temporary exists, empty
  kHalfWritten,       // half the bytes are in the temporary
  kWritten,           // all bytes written, not yet flushed
  kFileSynced,        // the temporary is on disk (fsync)
  kRenamed,           // renamed over the final path, the folder not yet flushed
  kFolderSynced,      // the folder is flushed: the step is durable
  kRemoved,           // removeFileDurably: unlinked, the folder not yet flushed
};
using WriteStepHook = void (*)(WriteStep step, const std::string& path);
void setWriteStepHook(WriteStepHook hook);

}  // namespace lanemap::io
