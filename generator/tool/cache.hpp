// The cache of `mbsgen run` (docs/cli.md, "The cache"): where it is, how an entry is checked,
// locked while in use, described, and evicted, and the `mbsgen cache` command.
//
// An entry is a directory named by the hash of its key, holding an artifact (the compiled solver
// "solve", or the "tape") and its record "<artifact>.sum", written last. The record holds the
// artifact's size and FNV-1a hash, and the inode, size and modification time it had when
// recorded: a run compares those (one stat, no read) and hashes the whole file only when they
// differ (a copied, touched or rewritten artifact). A run holds a shared lock (flock) on the
// entry's directory from before its check until the program it starts ends — the descriptor is
// inherited across exec — and eviction takes the exclusive lock without waiting, so that an
// entry in use is never evicted; an evicted entry is renamed aside first, so that a run never
// sees it half removed.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

namespace mbsgen::tool {

namespace fs = std::filesystem;

/// $MBSGEN_CACHE_DIR, else $XDG_CACHE_HOME/mbsgen, else ~/.cache/mbsgen, else a directory of
/// this user under the temporary directory.
fs::path cache_root();
/// Creates d (mode 0700) if missing; throws unless it is a directory of this user that others
/// cannot write to (the cache holds programs that `mbsgen run` executes).
void ensure_private_directory(const fs::path& d);
/// The whole file; throws when it cannot be read.
std::string read_file(const fs::path& p);

/// The record of an artifact (its content's size and hash, and its inode, size and time).
std::string artifact_record(const fs::path& file);
/// Whether dir holds a sound artifact with its record; why not otherwise (why stays empty when
/// the entry does not exist at all).
bool sound_artifact(const fs::path& dir, const std::string& artifact, std::string& why);

/// A shared lock on a cache entry, held by an open descriptor of its directory that is not
/// closed on exec: the program `mbsgen run` becomes holds it until it ends.
class EntryLock {
 public:
  /// The lock on dir, taken (waiting while an eviction holds it), or nothing when there is no
  /// entry at dir (missing, or evicted meanwhile).
  static std::optional<EntryLock> shared(const fs::path& dir);
  EntryLock(EntryLock&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }
  EntryLock& operator=(EntryLock&& other) noexcept;
  EntryLock(const EntryLock&) = delete;
  EntryLock& operator=(const EntryLock&) = delete;
  ~EntryLock();

 private:
  explicit EntryLock(int fd) : fd_(fd) {}
  int fd_;
};

/// Marks the entry as used now (its directory's modification time: the order of eviction).
void touch_entry(const fs::path& dir);
/// What `mbsgen cache list` shows of an entry, written into its build directory: the model
/// file's path, the scene, the kind ("solver" or "tape") and its options.
void describe_entry(const fs::path& work, const std::string& model_file, const std::string& scene,
                    const std::string& kind, const std::string& options);
/// Removes a damaged entry (renamed aside first); false when it could not.
bool discard_entry(const fs::path& dir);

/// The cache's size limit in bytes: $MBSGEN_CACHE_MAX_SIZE (a size such as 500M or 2G, or
/// "none"), else 4 GiB; nothing for none. Throws for a malformed value.
std::optional<std::uintmax_t> cache_limit();
/// Evicts the least recently used entries, never `keep` nor one in use, until the cache is
/// within its limit.
void enforce_cache_limit(const fs::path& keep);

/// A size such as 500M, 2G or 1.5GiB (binary units; bytes without one); a duration such as 30d,
/// 12h, 90m, 45s or 2w in seconds. Throw std::invalid_argument naming `what` and the units.
std::uintmax_t parse_size(const std::string& text, const std::string& what);
double parse_duration(const std::string& text, const std::string& what);

/// `mbsgen cache list`: every entry with its kind, size, last use, model, scene and options.
int cache_list();
/// `mbsgen cache info`: where the cache is, its entries, size and limit.
int cache_info();
/// `mbsgen cache clean`: removes the entries not in use — those last used longer ago than
/// older_than_s, then the least recently used until the cache is within max_size; every one
/// when neither is given. dry_run: says what it would remove.
int cache_clean(const std::optional<double>& older_than_s, const std::optional<std::uintmax_t>& max_size, bool dry_run);

}  // namespace mbsgen::tool
