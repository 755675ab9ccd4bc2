// The cache of `mbsgen run` and the `mbsgen cache` command (cache.hpp).
#include "cache.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace mbsgen::tool {

fs::path cache_root() {
  if (const char* d = std::getenv("MBSGEN_CACHE_DIR"); d && *d) return d;
  if (const char* d = std::getenv("XDG_CACHE_HOME"); d && *d) return fs::path(d) / "mbsgen";
  if (const char* d = std::getenv("HOME"); d && *d) return fs::path(d) / ".cache" / "mbsgen";
  return fs::temp_directory_path() / ("mbsgen-cache-" + std::to_string(::getuid()));
}

void ensure_private_directory(const fs::path& d) {
  if (!d.parent_path().empty()) fs::create_directories(d.parent_path());
  if (::mkdir(d.c_str(), 0700) != 0 && errno != EEXIST)
    throw std::runtime_error("cannot create the solver cache " + d.string() + ": " + std::strerror(errno));
  struct stat st;
  if (::lstat(d.c_str(), &st) != 0 || !S_ISDIR(st.st_mode) || st.st_uid != ::getuid() ||
      (st.st_mode & S_IWOTH))
    throw std::runtime_error("the solver cache " + d.string() +
                             " is not a directory of this user that others cannot write to; "
                             "set MBSGEN_CACHE_DIR to one");
}

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + p.string());
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

namespace {

// The content's part of a record: size and FNV-1a hash. It guards against damage (a truncated,
// rewritten or deleted artifact), not against someone who can write the cache.
std::string content_digest(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + file.string());
  std::uint64_t h = 1469598103934665603ULL;
  std::uintmax_t size = 0;
  std::string chunk(1 << 16, '\0');
  while (in.read(chunk.data(), static_cast<std::streamsize>(chunk.size())) || in.gcount() > 0) {
    const auto n = static_cast<std::size_t>(in.gcount());
    for (std::size_t i = 0; i < n; ++i) h = (h ^ static_cast<unsigned char>(chunk[i])) * 1099511628211ULL;
    size += n;
  }
  char line[80];
  std::snprintf(line, sizeof line, "size %ju fnv1a64 %016llx", size, static_cast<unsigned long long>(h));
  return line;
}

// The file's identity and state: what an unchanged artifact keeps.
struct Stamp {
  std::uintmax_t inode = 0, size = 0;
  long long mtime_ns = 0;
  bool operator==(const Stamp& o) const { return inode == o.inode && size == o.size && mtime_ns == o.mtime_ns; }
};

std::optional<Stamp> stamp_of(const fs::path& file) {
  struct stat st;
  if (::stat(file.c_str(), &st) != 0) return std::nullopt;
  return Stamp{static_cast<std::uintmax_t>(st.st_ino), static_cast<std::uintmax_t>(st.st_size),
               static_cast<long long>(st.st_mtim.tv_sec) * 1000000000LL + st.st_mtim.tv_nsec};
}

std::string stamp_text(const Stamp& s) {
  return " inode " + std::to_string(s.inode) + " bytes " + std::to_string(s.size) + " mtime " + std::to_string(s.mtime_ns);
}

// Writes text to file through a new file beside it renamed over it (a reader sees the old or the
// new record, whole); false when it could not.
bool replace_file(const fs::path& file, const std::string& text) {
  std::string name = file.string() + ".tmp-XXXXXX";
  const int fd = ::mkstemp(name.data());
  if (fd < 0) return false;
  const bool written = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  ::close(fd);
  if (!written || ::rename(name.c_str(), file.c_str()) != 0) {
    ::unlink(name.c_str());
    return false;
  }
  return true;
}

}  // namespace

std::string artifact_record(const fs::path& file) {
  const std::optional<Stamp> before = stamp_of(file);
  const std::string digest = content_digest(file);
  const std::optional<Stamp> after = stamp_of(file);
  // A file that changed while it was read gets no stamp: the next check reads it whole.
  return digest + (before && after && *before == *after ? stamp_text(*before) : std::string()) + "\n";
}

bool sound_artifact(const fs::path& dir, const std::string& artifact, std::string& why) {
  std::error_code ec;
  if (!fs::exists(dir, ec)) return false;
  const fs::path file = dir / artifact, record = dir / (artifact + ".sum");
  const std::string noun = artifact == "solve" ? "solver" : artifact;
  try {
    if (!fs::exists(record)) {
      why = "its record " + record.filename().string() + " is missing";
    } else if (!fs::exists(file)) {
      why = "the " + noun + " is missing";
    } else {
      const std::string recorded = read_file(record);
      const std::optional<Stamp> now = stamp_of(file);
      // Unchanged since it was recorded: sound without reading it.
      if (now && recorded.find(stamp_text(*now) + "\n") != std::string::npos) return true;
      const std::string digest = content_digest(file);
      if (recorded.rfind(digest, 0) != 0 || (recorded.size() > digest.size() && recorded[digest.size()] != ' ' &&
                                             recorded[digest.size()] != '\n')) {
        why = "the " + noun + " does not match its record";
      } else {
        replace_file(record, artifact_record(file));  // copied or touched: stamped anew (best effort)
      }
    }
  } catch (const std::exception& e) {
    why = e.what();
  }
  return why.empty();
}

std::optional<EntryLock> EntryLock::shared(const fs::path& dir) {
  // Not O_CLOEXEC: the program this process becomes keeps the lock.
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd < 0) return std::nullopt;
  while (::flock(fd, LOCK_SH) != 0)
    if (errno != EINTR) {
      ::close(fd);
      return std::nullopt;
    }
  // Evicted while this run waited: the directory locked is no longer the entry.
  struct stat locked, now;
  if (::fstat(fd, &locked) != 0 || ::stat(dir.c_str(), &now) != 0 || locked.st_ino != now.st_ino ||
      locked.st_dev != now.st_dev) {
    ::close(fd);
    return std::nullopt;
  }
  return EntryLock(fd);
}

EntryLock& EntryLock::operator=(EntryLock&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = other.fd_;
    other.fd_ = -1;
  }
  return *this;
}

EntryLock::~EntryLock() {
  if (fd_ >= 0) ::close(fd_);
}

void touch_entry(const fs::path& dir) { ::utimensat(AT_FDCWD, dir.c_str(), nullptr, 0); }

void describe_entry(const fs::path& work, const std::string& model_file, const std::string& scene,
                    const std::string& kind, const std::string& options) {
  // One line each: a control character of a name (data) is shown as '?'.
  auto line = [](std::string s) {
    for (char& c : s)
      if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
    return s;
  };
  std::error_code ec;
  const fs::path model = fs::absolute(model_file, ec);
  std::ofstream out(work / "entry", std::ios::binary);
  out << "model " << line(ec ? model_file : model.string()) << "\nscene " << line(scene) << "\nkind " << kind
      << "\noptions " << line(options) << "\n";
  if (!out) throw std::runtime_error("cannot write " + (work / "entry").string());
}

namespace {

// Renames dir to a new name beside it (an empty directory made by mkdtemp, which rename
// replaces), then removes it; false when the rename failed.
bool remove_aside(const fs::path& dir) {
  std::string name = dir.string() + ".old-XXXXXX";
  if (!::mkdtemp(name.data())) return false;
  if (::rename(dir.c_str(), name.c_str()) != 0) {
    ::rmdir(name.c_str());
    return false;
  }
  std::error_code ec;
  fs::remove_all(name, ec);
  return true;
}

// Evicts the entry dir unless a run holds it (or another eviction took it first).
bool evict(const fs::path& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd < 0) return false;
  bool removed = false;
  if (::flock(fd, LOCK_EX | LOCK_NB) == 0) removed = remove_aside(dir);
  ::close(fd);
  return removed;
}

bool is_key(const std::string& name) {
  return name.size() == 16 && std::all_of(name.begin(), name.end(), [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
         });
}

struct Entry {
  fs::path dir;
  std::string kind, id, model, scene, options;
  std::uintmax_t bytes = 0;
  std::time_t used = 0;  // the directory's modification time
};

std::uintmax_t bytes_under(const fs::path& dir) {
  std::uintmax_t n = 0;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file(ec)) n += it->file_size(ec);
  return n;
}

std::time_t modified(const fs::path& p) {
  struct stat st;
  return ::stat(p.c_str(), &st) == 0 ? st.st_mtim.tv_sec : 0;
}

// The entries of the cache (directories named by a key), and the directories of builds under
// way or of removals interrupted (`.tmp-`, `.old-`) in others.
std::vector<Entry> entries(const fs::path& root, std::vector<Entry>* others = nullptr) {
  std::vector<Entry> out;
  std::error_code ec;
  for (fs::directory_iterator it(root, ec), end; !ec && it != end; it.increment(ec)) {
    if (!it->is_directory(ec) || it->is_symlink(ec)) continue;
    Entry e;
    e.dir = it->path();
    e.bytes = bytes_under(e.dir);
    e.used = modified(e.dir);
    const std::string name = e.dir.filename().string();
    if (!is_key(name)) {
      if (others && name.size() > 16 && is_key(name.substr(0, 16))) others->push_back(e);
      continue;
    }
    e.kind = fs::exists(e.dir / "solve.sum", ec)     ? "solver"
             : fs::exists(e.dir / "tape.sum", ec)    ? "tape"
             : fs::exists(e.dir / "kernels.sum", ec) ? "kernels"
                                                     : "damaged";
    try {
      if (fs::exists(e.dir / "id", ec)) e.id = read_file(e.dir / "id");
      if (fs::exists(e.dir / "entry", ec)) {
        std::istringstream in(read_file(e.dir / "entry"));
        for (std::string line; std::getline(in, line);) {
          const auto space = line.find(' ');
          const std::string field = line.substr(0, space), value = space == std::string::npos ? "" : line.substr(space + 1);
          if (field == "model") e.model = value;
          if (field == "scene") e.scene = value;
          if (field == "options") e.options = value;
        }
      }
    } catch (const std::exception&) {
    }
    out.push_back(std::move(e));
  }
  return out;
}

std::string human_size(std::uintmax_t bytes) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  double v = static_cast<double>(bytes);
  int u = 0;
  while (v >= 1024 && u < 4) v /= 1024, ++u;
  char s[32];
  std::snprintf(s, sizeof s, u == 0 ? "%.0f %s" : "%.1f %s", v, units[u]);
  return s;
}

std::string utc_time(std::time_t t) {
  char s[32];
  std::tm tm{};
  ::gmtime_r(&t, &tm);
  std::strftime(s, sizeof s, "%Y-%m-%d %H:%M:%S", &tm);
  return s;
}

// A number with a unit of `units` (name, factor); throws std::invalid_argument naming `what`.
double with_unit(const std::string& text, const std::vector<std::pair<std::string, double>>& units,
                 const std::string& what) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  const std::string unit = text.substr(used);
  if (used > 0 && std::isfinite(v) && v >= 0)
    for (const auto& [name, factor] : units)
      if (unit == name) return v * factor;
  std::string names;
  for (const auto& [name, factor] : units) names += (names.empty() ? "" : ", ") + (name.empty() ? "(none)" : name);
  throw std::invalid_argument(what + " '" + text + "' is not a number ≥ 0 with a unit (" + names + ")");
}

}  // namespace

std::uintmax_t parse_size(const std::string& text, const std::string& what) {
  const double k = 1024;
  return static_cast<std::uintmax_t>(with_unit(text, {{"", 1}, {"B", 1}, {"K", k}, {"KiB", k}, {"M", k * k}, {"MiB", k * k},
                                                     {"G", k * k * k}, {"GiB", k * k * k}, {"T", k * k * k * k},
                                                     {"TiB", k * k * k * k}},
                                               what));
}

double parse_duration(const std::string& text, const std::string& what) {
  return with_unit(text, {{"s", 1}, {"m", 60}, {"h", 3600}, {"d", 86400}, {"w", 7 * 86400}}, what);
}

std::optional<std::uintmax_t> cache_limit() {
  const char* v = std::getenv("MBSGEN_CACHE_MAX_SIZE");
  if (!v || !*v) return std::uintmax_t{4} << 30;
  if (std::string(v) == "none") return std::nullopt;
  return parse_size(v, "MBSGEN_CACHE_MAX_SIZE");
}

bool discard_entry(const fs::path& dir) { return remove_aside(dir); }

void enforce_cache_limit(const fs::path& keep) {
  const std::optional<std::uintmax_t> limit = cache_limit();
  if (!limit) return;
  std::vector<Entry> all = entries(keep.parent_path());
  std::uintmax_t total = 0;
  for (const Entry& e : all) total += e.bytes;
  std::sort(all.begin(), all.end(), [](const Entry& a, const Entry& b) { return a.used < b.used; });
  for (const Entry& e : all) {
    if (total <= *limit) break;
    if (e.dir != keep && evict(e.dir)) total -= e.bytes;
  }
}

// ---- mbsgen cache ----

int cache_list() {
  const fs::path root = cache_root();
  std::vector<Entry> all = entries(root);
  std::sort(all.begin(), all.end(), [](const Entry& a, const Entry& b) { return a.used > b.used; });
  std::cout << "ENTRY             KIND     SIZE        LAST USE (UTC)       MODEL  SCENE  OPTIONS  FILE\n";
  std::uintmax_t total = 0;
  for (const Entry& e : all) {
    char head[96];
    std::snprintf(head, sizeof head, "%-16s  %-7s  %10s  %s", e.dir.filename().c_str(), e.kind.c_str(),
                  human_size(e.bytes).c_str(), utc_time(e.used).c_str());
    auto shown = [](const std::string& s) { return s.empty() ? std::string("-") : s; };
    std::cout << head << "  " << shown(e.id) << "  " << shown(e.scene) << "  " << shown(e.options) << "  "
              << shown(e.model) << "\n";
    total += e.bytes;
  }
  std::cout << all.size() << " entries, " << human_size(total) << " in " << root.string() << "\n";
  return 0;
}

int cache_info() {
  const fs::path root = cache_root();
  std::vector<Entry> building;
  const std::vector<Entry> all = entries(root, &building);
  std::size_t solvers = 0, tapes = 0, kernels = 0;
  std::uintmax_t total = 0;
  for (const Entry& e : all) {
    solvers += e.kind == "solver";
    tapes += e.kind == "tape";
    kernels += e.kind == "kernels";
    total += e.bytes;
  }
  for (const Entry& e : building) total += e.bytes;
  std::cout << "cache: " << root.string() << (fs::exists(root) ? "" : " (not created yet)") << "\n";
  std::cout << "entries: " << all.size() << " (" << solvers << " solvers, " << tapes << " tapes, " << kernels
            << " compiled kernels, " << all.size() - solvers - tapes - kernels << " damaged), " << building.size() << " builds or removals under way\n";
  std::cout << "size: " << human_size(total) << " (" << total << " bytes)\n";
  const std::optional<std::uintmax_t> limit = cache_limit();
  const char* set = std::getenv("MBSGEN_CACHE_MAX_SIZE");
  std::cout << "limit: " << (limit ? human_size(*limit) : std::string("none"))
            << (set && *set ? " (MBSGEN_CACHE_MAX_SIZE)" : " (the default; MBSGEN_CACHE_MAX_SIZE sets another)")
            << ": the least recently used entries are evicted after a build\n";
  return 0;
}

int cache_clean(const std::optional<double>& older_than_s, const std::optional<std::uintmax_t>& max_size, bool dry_run) {
  const fs::path root = cache_root();
  std::vector<Entry> leftovers;
  std::vector<Entry> all = entries(root, &leftovers);
  std::sort(all.begin(), all.end(), [](const Entry& a, const Entry& b) { return a.used < b.used; });
  const std::time_t now = std::time(nullptr);
  std::uintmax_t total = 0;
  for (const Entry& e : all) total += e.bytes;
  std::size_t removed = 0, busy = 0;
  std::uintmax_t freed = 0;
  for (const Entry& e : all) {
    const bool old = older_than_s && static_cast<double>(now - e.used) > *older_than_s;
    const bool over = max_size && total > *max_size;
    const bool chosen = (!older_than_s && !max_size) || old || over;
    if (!chosen) continue;
    if (dry_run) {
      std::cout << "would remove " << e.dir.string() << " (" << human_size(e.bytes) << ")\n";
    } else if (!evict(e.dir)) {
      ++busy;
      continue;
    }
    ++removed, freed += e.bytes, total -= e.bytes;
  }
  // Removals interrupted, and builds interrupted a day ago or more (a running build is younger).
  for (const Entry& e : leftovers) {
    const std::string name = e.dir.filename().string();
    const bool stale = name.find(".old-") != std::string::npos || now - e.used > 86400;
    if (!stale || dry_run) continue;
    std::error_code ec;
    fs::remove_all(e.dir, ec);
    if (!ec) freed += e.bytes;
  }
  std::cout << (dry_run ? "would remove " : "removed ") << removed << " entries (" << human_size(freed) << "); "
            << all.size() - removed - busy << " kept"
            << (busy ? ", " + std::to_string(busy) + " in use by a running solver (kept)" : std::string()) << "\n";
  return 0;
}

}  // namespace mbsgen::tool
