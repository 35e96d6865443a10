#include "output_folder.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <corrlap/core/error.hpp>
#include <cstring>
#include <filesystem>

namespace corrlap {
namespace {

namespace fs = std::filesystem;

// "out/" and "out" are the same folder: without the trailing separator, parent_path() is the
// folder that holds it.
fs::path normalized(const std::string& path) {
  fs::path p = fs::path(path).lexically_normal();
  if (!p.has_filename() && p.has_relative_path()) p = p.parent_path();
  return p;
}

// Built by appending: GCC 12 at -O3 warns (-Wrestrict, a false positive) on "'" + a temporary.
std::string quoted(const fs::path& p) {
  std::string q = "'";
  q += p.string();
  q += "'";
  return q;
}

// A name no other run of this or another process uses beside `base`.
std::string temporary_name(const fs::path& base) {
  static std::atomic<int> counter{0};
  std::string name = ".";
  name += base.filename().string();
  name += ".corrlap-tmp-" + std::to_string(::getpid()) + "-" + std::to_string(++counter);
  return name;
}

// The nearest existing ancestor of `p` (the current folder for a relative name); IoError when it
// is not a folder or not writable. `what` is "output folder" or "output file".
fs::path writable_ancestor(const fs::path& p, const std::string& given, const char* what,
                           const std::string& parameter) {
  for (fs::path a = p.parent_path();; a = a.parent_path()) {
    const fs::path probe = a.empty() ? fs::path(".") : a;
    std::error_code ec;
    const fs::file_status s = fs::status(probe, ec);
    if (fs::exists(s)) {
      if (!fs::is_directory(s))
        throw IoError(std::string(what) + " '" + given + "' lies under " + quoted(probe) +
                          ", which is a file, not a folder; choose a path in a folder",
                      parameter);
      if (::access(probe.c_str(), W_OK | X_OK) != 0)
        throw IoError(std::string(what) + " '" + given + "': cannot write in " + quoted(probe) + " (" +
                          std::strerror(errno) + "); choose a folder you can write to",
                      parameter);
      return probe;
    }
    if (a.empty() || a == a.root_path()) return probe;  // nothing exists above: let creating tell why
  }
}

}  // namespace

void check_output_folder(const std::string& path, const std::string& parameter) {
  if (path.empty()) throw IoError("output folder: the name is empty; name a folder", parameter);
  const fs::path p = normalized(path);
  std::error_code ec;
  const fs::file_status s = fs::status(p, ec);
  if (fs::exists(s)) {
    if (fs::is_regular_file(s))
      throw IoError("output folder '" + path +
                        "' is an existing file; the output is a folder: name a new or an "
                        "existing folder",
                    parameter);
    if (!fs::is_directory(s))
      throw IoError("output folder '" + path +
                        "' is a special file (a device, pipe or socket), not a folder; name a "
                        "new or an existing folder",
                    parameter);
    if (::access(p.c_str(), W_OK | X_OK) != 0)
      throw IoError("output folder '" + path + "': cannot write in it (" + std::strerror(errno) +
                        "); choose a folder you can write to",
                    parameter);
    return;
  }
  (void)writable_ancestor(p, path, "output folder", parameter);
}

void check_output_file(const std::string& path, const std::string& parameter) {
  if (path.empty()) throw IoError("output file: the name is empty; name a file", parameter);
  const fs::path p(path);
  std::error_code ec;
  const fs::file_status s = fs::status(p, ec);
  if (fs::is_directory(s)) throw IoError("output file '" + path + "' is an existing folder; name a file", parameter);
  if (fs::exists(s) && !fs::is_regular_file(s)) return;  // /dev/null, a pipe: written in place
  if (!p.has_filename()) throw IoError("output file '" + path + "' names a folder; name a file", parameter);
  const fs::path folder = writable_ancestor(p, path, "output file", parameter);
  // The writers create files, not folders: the file's folder must exist.
  const fs::path parent = p.parent_path().empty() ? fs::path(".") : p.parent_path();
  if (folder != parent)
    throw IoError("output file '" + path + "': the folder " + quoted(parent) + " does not exist; create it first",
                  parameter);
}

OutputFolder::OutputFolder(const std::string& folder, const std::string& parameter, Mode mode)
    : folder_(folder), parameter_(parameter), mode_(mode) {
  check_output_folder(folder, parameter);
  fs::path target = normalized(fs::absolute(normalized(folder)).string());
  target_ = target.string();
  if (!target.has_parent_path() || target == target.root_path()) mode_ = Mode::InPlace;  // "/": no sibling
  const auto create = [&](const fs::path& dir) {
    std::error_code ec;
    if (!fs::create_directory(dir, ec) && ec) {
      rollback();
      throw IoError("output folder '" + folder_ + "': cannot create " + quoted(dir) + " (" + ec.message() +
                        "); choose a folder you can write to",
                    parameter_);
    }
  };
  // The missing parents, outermost first; recorded so that a rollback removes them again.
  std::vector<fs::path> missing;
  for (fs::path a = target.parent_path(); !a.empty() && !fs::exists(a); a = a.parent_path()) {
    missing.insert(missing.begin(), a);
    if (a == a.root_path()) break;
  }
  for (const fs::path& dir : missing) {
    create(dir);
    created_.push_back(dir.string());
  }
  if (mode_ == Mode::Staged) {
    // Beside an absent destination, so that commit() is one rename; inside an existing one, which
    // is the only folder the user must be able to write to (`--out /tmp`).
    const fs::path temp = (fs::is_directory(target) ? target : target.parent_path()) / temporary_name(target);
    create(temp);
    path_ = temp.string();
    return;
  }
  path_ = normalized(folder).string();  // as the user named it: the command's messages show it
  if (fs::exists(target)) {
    for (const fs::directory_entry& e : fs::directory_iterator(target))
      existing_.push_back(e.path().filename().string());
  } else {
    create(target);
    created_target_ = true;
  }
}

OutputFolder::~OutputFolder() {
  if (!committed_) rollback();
}

void OutputFolder::rollback() noexcept {
  std::error_code ec;
  if (mode_ == Mode::Staged && !path_.empty()) {
    fs::remove_all(path_, ec);
  } else if (mode_ == Mode::InPlace && !path_.empty()) {
    if (created_target_) {
      fs::remove_all(target_, ec);
    } else {
      std::vector<fs::path> added;
      for (fs::directory_iterator it(target_, ec), end; !ec && it != end; it.increment(ec))
        if (std::find(existing_.begin(), existing_.end(), it->path().filename().string()) == existing_.end())
          added.push_back(it->path());
      for (const fs::path& p : added) fs::remove_all(p, ec);
    }
  }
  // Only folders that are empty again: another process may have put something in them.
  for (auto it = created_.rbegin(); it != created_.rend(); ++it) fs::remove(*it, ec);
  created_.clear();
}

namespace {

// Moves every entry of `from` into `to`, replacing files of the same name and merging folders.
void move_into(const fs::path& from, const fs::path& to, const std::string& folder, const std::string& parameter) {
  std::vector<fs::path> entries;
  for (const fs::directory_entry& e : fs::directory_iterator(from)) entries.push_back(e.path());
  for (const fs::path& source : entries) {
    const fs::path dest = to / source.filename();
    std::error_code ec;
    if (fs::is_directory(source) && fs::is_directory(dest)) {
      move_into(source, dest, folder, parameter);
      continue;
    }
    fs::rename(source, dest, ec);
    if (ec)
      throw IoError("output folder '" + folder + "': cannot put " + quoted(source.filename()) + " in place of " +
                        quoted(dest) + " (" + ec.message() + "); move or remove " + quoted(dest) + " and run again",
                    parameter);
  }
}

}  // namespace

void OutputFolder::commit() {
  if (committed_) return;
  if (mode_ == Mode::Staged) {
    std::error_code ec;
    // Into an absent destination: one rename. Into an existing one (or one that appeared since),
    // file by file.
    if (!fs::exists(target_)) fs::rename(path_, target_, ec);
    if (fs::exists(target_) && fs::exists(path_)) {
      move_into(path_, target_, folder_, parameter_);
      fs::remove_all(path_, ec);
    } else if (ec) {
      throw IoError(
          "output folder '" + folder_ + "': cannot rename the finished output into place (" + ec.message() + ")",
          parameter_);
    }
  }
  committed_ = true;
  created_.clear();
}

StagedFile::StagedFile(const std::string& file, const std::string& parameter) : file_(file), parameter_(parameter) {
  check_output_file(file, parameter);
  std::error_code ec;
  const fs::file_status s = fs::status(file, ec);
  if (fs::exists(s) && !fs::is_regular_file(s)) {
    path_ = file;
    committed_ = true;  // nothing to rename or remove
    return;
  }
  const fs::path p(file);
  path_ = (p.parent_path() / (temporary_name(p) + p.extension().string())).string();
  // Created now, so that an unwritable place (/proc) is refused before any computation.
  const int fd = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0666);
  if (fd < 0)
    throw IoError("output file '" + file + "': cannot create a file in " +
                      quoted(p.parent_path().empty() ? fs::path(".") : p.parent_path()) + " (" + std::strerror(errno) +
                      "); choose a folder you can write to",
                  parameter);
  ::close(fd);
}

StagedFile::~StagedFile() {
  if (committed_) return;
  std::error_code ec;
  fs::remove(path_, ec);
}

void StagedFile::commit() {
  if (committed_) return;
  std::error_code ec;
  fs::rename(path_, file_, ec);
  if (ec)
    throw IoError("output file '" + file_ + "': cannot rename the finished file into place (" + ec.message() + ")",
                  parameter_);
  committed_ = true;
}

}  // namespace corrlap
