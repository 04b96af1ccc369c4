#include "stereodet/util/run_manifest.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <nlohmann/json.hpp>
#include <system_error>

#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/hash.h"

namespace stereodet {
namespace fs = std::filesystem;

std::string RunManifestToJson(const RunManifest& manifest) {
  nlohmann::ordered_json j;
  j["tool"] = manifest.tool;
  j["version"] = manifest.version;
  j["command_line"] = manifest.command_line;
  j["inputs"] = nlohmann::ordered_json::object();
  for (const auto& [name, path] : manifest.inputs) j["inputs"][name] = path;
  nlohmann::ordered_json settings;
  try {
    settings = nlohmann::ordered_json::parse(manifest.settings_json);
  } catch (const nlohmann::json::exception& e) {
    STEREODET_THROW_ARG() << "RunManifest: settings are not JSON: " << e.what();
  }
  STEREODET_CHECK(settings.is_object()) << "RunManifest: settings must be a JSON object";
  j["settings"] = settings;
  j["frames"] = nlohmann::ordered_json::object();
  for (const auto& [id, hash] : manifest.frames) j["frames"][id] = hash;
  return j.dump(2) + "\n";
}

RunManifest RunManifestFromJson(const std::string& text, const std::string& source) {
  nlohmann::ordered_json j;
  try {
    j = nlohmann::ordered_json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw ParseError(source, 0, "", std::string("not valid JSON: ") + e.what());
  }
  std::string field;
  try {
    RunManifest manifest;
    field = "tool";
    manifest.tool = j.at(field).get<std::string>();
    field = "version";
    manifest.version = j.at(field).get<std::string>();
    field = "command_line";
    manifest.command_line = j.at(field).get<std::string>();
    // Objects, as RunManifestToJson writes them (and can write back).
    for (const char* object_field : {"inputs", "settings", "frames"}) {
      field = object_field;
      if (!j.at(field).is_object()) throw ParseError(source, 0, field, "must be a JSON object");
    }
    field = "inputs";
    for (const auto& [name, path] : j.at(field).items()) {
      manifest.inputs.emplace_back(name, path.get<std::string>());
    }
    field = "settings";
    manifest.settings_json = j.at(field).dump();
    field = "frames";
    for (const auto& [id, hash] : j.at(field).items()) {
      manifest.frames.emplace_back(id, hash.get<std::string>());
    }
    return manifest;
  } catch (const nlohmann::json::exception& e) {
    throw ParseError(source, 0, field, e.what());
  }
}

void WriteRunManifest(const fs::path& dir, const RunManifest& manifest) {
  WriteFileAtomically(dir / kRunManifestFile, RunManifestToJson(manifest));
}

std::optional<RunManifest> ReadRunManifest(const fs::path& dir) {
  const fs::path path = dir / kRunManifestFile;
  std::error_code ec;
  if (!fs::exists(path, ec)) return std::nullopt;
  return RunManifestFromJson(ReadFile(path), path.string());
}

namespace {

// Canonical where the path exists, its longest existing head canonical and the rest as written
// otherwise; always absolute and without a trailing separator.
fs::path Resolved(const fs::path& path) {
  std::error_code ec;
  fs::path resolved = fs::weakly_canonical(fs::absolute(path, ec), ec);
  if (ec) resolved = fs::absolute(path).lexically_normal();
  if (!resolved.has_filename() && resolved.has_parent_path()) resolved = resolved.parent_path();
  return resolved;
}

// Whether `inner` is `outer` or lies below it (component-wise, so /a/bc is not inside /a/b).
bool IsWithin(const fs::path& inner, const fs::path& outer) {
  auto i = inner.begin();
  for (auto o = outer.begin(); o != outer.end(); ++o, ++i) {
    if (i == inner.end() || *i != *o) return false;
  }
  return true;
}

}  // namespace

void CheckOutputDoesNotOverlapInputs(const std::string& out_name, const fs::path& out,
                                     const std::vector<std::pair<std::string, fs::path>>& inputs) {
  if (out.empty()) return;
  const fs::path out_path = Resolved(out);
  for (const auto& [name, input] : inputs) {
    if (input.empty()) continue;
    const fs::path in_path = Resolved(input);
    if (IsWithin(out_path, in_path)) {
      STEREODET_THROW_ARG() << out_name << " " << out.string()
                            << (out_path == in_path ? " is the input " : " is inside the input ")
                            << name << " " << in_path.string()
                            << "; writing there would overwrite it; choose a folder outside it";
    }
    if (IsWithin(in_path, out_path)) {
      STEREODET_THROW_ARG() << out_name << " " << out.string() << " holds the input " << name << " "
                            << in_path.string()
                            << "; writing there would overwrite it; choose a folder outside it";
    }
  }
}

std::string HashFileHex(const fs::path& path) { return HashHex(Fnv1a64(ReadFile(path))); }

void CheckFolderWritable(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  STEREODET_CHECK_IO(!ec) << "cannot create folder " << dir.string() << ": " << ec.message();
  STEREODET_CHECK_IO(fs::is_directory(dir, ec)) << dir.string() << " is not a folder";
  try {
    WriteFileAtomically(dir / ".write-probe", "");
  } catch (const std::runtime_error&) {
    STEREODET_THROW_IO() << "cannot write into folder " << dir.string()
                         << " (read-only or not permitted)";
  }
  fs::remove(dir / ".write-probe", ec);
}

OutputLock::OutputLock(const fs::path& dir, const std::string& kind, bool wait) {
  fs::path folder = dir.lexically_normal();
  if (!folder.has_filename() && folder.has_parent_path()) folder = folder.parent_path();
  path_ = folder.parent_path() / ("." + folder.filename().string() + "." + kind);
  std::error_code ec;
  if (!path_.parent_path().empty()) fs::create_directories(path_.parent_path(), ec);
  // The file may be unlinked by the holder between our open and our flock: then we hold a lock on
  // a file nobody else sees, so check that the path still names the file we locked, and retry.
  for (int attempt = 0; attempt < 100; ++attempt) {
    const int fd = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    STEREODET_CHECK_IO(fd >= 0) << "cannot create the lock " << path_.string() << " for "
                                << folder.string() << ": " << std::strerror(errno);
    if (::flock(fd, wait ? LOCK_EX : LOCK_EX | LOCK_NB) != 0) {
      const int error = errno;
      ::close(fd);
      STEREODET_CHECK_IO(error != EWOULDBLOCK)
          << "another run is writing into " << folder.string() << " (lock " << path_.string()
          << " held); wait for it or use another --out";
      STEREODET_THROW_IO() << "cannot lock " << path_.string() << ": " << std::strerror(error);
    }
    struct stat locked {
    }, named{};
    if (::fstat(fd, &locked) == 0 && ::stat(path_.c_str(), &named) == 0 &&
        locked.st_ino == named.st_ino && locked.st_dev == named.st_dev) {
      fd_ = fd;
      return;
    }
    ::close(fd);
  }
  STEREODET_THROW_IO() << "cannot lock " << path_.string() << ": it keeps being replaced";
}

OutputLock::~OutputLock() {
  if (fd_ < 0) return;
  ::unlink(path_.c_str());  // while still holding the lock (see the constructor)
  ::close(fd_);
}

}  // namespace stereodet
