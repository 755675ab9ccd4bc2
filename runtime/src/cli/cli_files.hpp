// Files the command lines write (docs/cli.md "Files"): never into a special file, never over a
// file mbsgen did not write, and all of a command's files or none.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace mbsgen::cli {

/// Throws Error when `path` exists and is not a regular file: a FIFO would block the writer
/// forever, a device or socket is no file to replace, and a symbolic link or directory would be
/// replaced rather than written. `what` names the option in the message (e.g. "--plot").
void refuse_special_file(const std::filesystem::path& path, const std::string& what);

struct OutputFile {
  std::filesystem::path path;
  std::string content;
};

/// Throws Error when `path` exists and is not a directory (following links): an output directory
/// that is a regular file, a FIFO or a device. `what` names the option (e.g. "matrices --out").
void refuse_non_directory(const std::filesystem::path& path, const std::string& what);
/// Throws Error, as write_all_or_nothing would, when one of paths exists and is not a regular file
/// whose first 400 bytes contain `marker`: for a command that checks its targets before long work.
void refuse_foreign_files(const std::vector<std::filesystem::path>& paths, const std::string& marker,
                          const std::string& what);

/// Writes every file or none. Every target is checked first: it must be absent, or a regular file
/// whose first 400 bytes contain `marker` (mbsgen wrote it); otherwise Error "refusing to
/// overwrite …" and nothing is written. Then each content goes to a new temporary file beside its
/// target (mkstemps, mode 0666 & ~umask) and all are renamed into place. A failed write throws
/// Error and leaves no temporary file.
void write_all_or_nothing(const std::vector<OutputFile>& files, const std::string& marker,
                          const std::string& what);

}  // namespace mbsgen::cli
