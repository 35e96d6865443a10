#pragma once
// Outputs that appear whole or not at all. A command checks its output paths before it computes
// anything, writes into a hidden temporary sibling of each destination and commits at the end:
// a failure (an exception) leaves nothing new behind, or the previous result untouched.
//
//   OutputFolder out(dir);             // checked now; the files go to out.path()
//   write_mesh(out.file("a.ply"), m);  // ... computing and writing ...
//   out.commit();                      // out.path() becomes `dir`
//
// Every error is an IoError naming the path, what is wrong with it and a way out; its parameter
// is the one given to the constructor ("out"), so a front end can name its own option.
#include <string>
#include <vector>

namespace corrlap {

/// Throws IoError (with `parameter`) unless `path` can become an output folder: it is empty, an
/// existing file or special file (/dev/null), lies under a file, or its nearest existing folder
/// is not writable. Creates nothing.
void check_output_folder(const std::string& path, const std::string& parameter = "out");

/// The same for one output file: refused when it is empty, an existing folder, lies under a file,
/// or its folder does not exist or is not writable. An existing special file (/dev/null, a pipe)
/// is accepted: it is written in place, as nothing can be renamed onto it.
void check_output_file(const std::string& path, const std::string& parameter = "out");

/// An output folder written atomically.
///
/// Staged (the default): the files are written into a hidden temporary folder beside the
/// destination (same parent, so commit() is a rename), or inside it when it exists. commit()
/// renames it into place when the destination does not exist; when it does (a re-run into the
/// same folder), each produced file is moved into it, replacing a file of the same name; the
/// folder's other files stay.
///
/// InPlace: the files are written into the destination itself (for a study whose rows must
/// survive an interrupted run, to be resumed). A rollback removes the files and folders that were
/// not there at construction; files that were are kept as they are.
///
/// Without commit() (an exception, an early return), the destructor rolls back: the temporary
/// folder, the files created in place, and the parent folders the constructor created are removed.
/// A process killed by a signal may leave the hidden temporary folder (".NAME.corrlap-tmp-*").
class OutputFolder {
 public:
  enum class Mode { Staged, InPlace };

  /// Checks `folder` (check_output_folder), creates its missing parents and the temporary folder
  /// (Staged) or the folder itself (InPlace). IoError when any of that fails.
  explicit OutputFolder(const std::string& folder, const std::string& parameter = "out", Mode mode = Mode::Staged);
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  /// Where the command writes: the temporary folder (Staged) or the destination (InPlace).
  const std::string& path() const { return path_; }
  /// path() / name.
  std::string file(const std::string& name) const { return path_ + "/" + name; }
  /// The destination, as given.
  const std::string& folder() const { return folder_; }

  /// Puts the files in place (see the class comment). IoError when a produced file cannot replace
  /// the destination's entry of the same name (e.g. a folder there); the files moved so far stay.
  void commit();

 private:
  void rollback() noexcept;

  std::string folder_, parameter_, target_, path_;
  Mode mode_;
  bool committed_ = false;
  bool created_target_ = false;        // InPlace: the destination did not exist
  std::vector<std::string> created_;   // parent folders created, outermost first
  std::vector<std::string> existing_;  // InPlace: the names in the destination at construction
};

/// One output file written atomically: the command writes path(), a hidden temporary sibling with
/// the same extension (the writers choose the format by it), and commit() renames it onto the
/// destination. Without commit() the temporary file is removed. An existing special file
/// (/dev/null) is written directly: path() is the destination and commit() does nothing.
class StagedFile {
 public:
  /// Checks `file` (check_output_file). IoError when it cannot be written.
  explicit StagedFile(const std::string& file, const std::string& parameter = "out");
  ~StagedFile();
  StagedFile(const StagedFile&) = delete;
  StagedFile& operator=(const StagedFile&) = delete;

  const std::string& path() const { return path_; }
  const std::string& file() const { return file_; }
  /// Renames path() onto the destination (nothing when path() was not written).
  void commit();

 private:
  std::string file_, parameter_, path_;
  bool committed_ = false;
};

}  // namespace corrlap
