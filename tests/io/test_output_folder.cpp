// io/output_folder: outputs put in place whole at commit, or nothing left behind.
#include <doctest/doctest.h>

#include <corrlap/core/error.hpp>
#include <corrlap/io/output_folder.hpp>
#include <filesystem>
#include <set>
#include <string>

#include "test_support.hpp"

namespace fs = std::filesystem;
using corrlap::IoError;
using corrlap::OutputFolder;
using corrlap::StagedFile;
using corrlap::test::read_text;
using corrlap::test::tmp_path;
using corrlap::test::write_text;

namespace {

// A fresh, empty scratch folder per test (ctest runs the cases as concurrent processes).
std::string scratch(const std::string& name) {
  const std::string dir = tmp_path("output_folder_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::set<std::string> names(const std::string& dir) {
  std::set<std::string> s;
  for (const auto& e : fs::directory_iterator(dir)) s.insert(e.path().filename().string());
  return s;
}

// The message of the IoError `f` throws, with its parameter.
template <class F>
std::string io_error(F&& f, std::string* parameter = nullptr) {
  try {
    f();
  } catch (const IoError& e) {
    if (parameter) *parameter = e.parameter();
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST_CASE("OutputFolder: commit renames the staged folder into place, nothing shows before") {
  const std::string dir = scratch("commit");
  {
    OutputFolder out(dir + "/result");
    CHECK(out.path() != dir + "/result");
    CHECK(fs::path(out.path()).parent_path() == fs::path(dir));
    CHECK(fs::path(out.path()).filename().string().front() == '.');  // hidden
    write_text(out.file("a.txt"), "a");
    CHECK_FALSE(fs::exists(dir + "/result"));
    out.commit();
  }
  CHECK(names(dir) == std::set<std::string>{"result"});
  CHECK(read_text(dir + "/result/a.txt") == "a");
}

TEST_CASE("OutputFolder: without commit, nothing is left, not even the parents it created") {
  const std::string dir = scratch("rollback");
  {
    OutputFolder out(dir + "/p/q/result");
    write_text(out.file("a.txt"), "a");
    CHECK(fs::is_directory(dir + "/p/q"));
  }
  CHECK(names(dir).empty());
  // An exception between construction and commit: the same.
  CHECK_THROWS_AS(([&] {
                    OutputFolder out(dir + "/r");
                    write_text(out.file("a.txt"), "a");
                    throw IoError("failed");
                  }()),
                  IoError);
  CHECK(names(dir).empty());
}

TEST_CASE("OutputFolder: into an existing folder, produced files replace their namesakes and others stay") {
  const std::string dir = scratch("existing");
  fs::create_directories(dir + "/result/sub");
  write_text(dir + "/result/a.txt", "old a");
  write_text(dir + "/result/mine.txt", "the user's");
  write_text(dir + "/result/sub/old.txt", "old");
  {
    OutputFolder out(dir + "/result/");  // a trailing separator names the same folder
    write_text(out.file("a.txt"), "new a");
    write_text(out.file("b.txt"), "b");
    fs::create_directories(out.file("sub"));
    write_text(out.file("sub/new.txt"), "new");
    CHECK(read_text(dir + "/result/a.txt") == "old a");  // untouched until commit
    out.commit();
  }
  CHECK(names(dir) == std::set<std::string>{"result"});
  CHECK(names(dir + "/result") == std::set<std::string>{"a.txt", "b.txt", "mine.txt", "sub"});
  CHECK(read_text(dir + "/result/a.txt") == "new a");
  CHECK(read_text(dir + "/result/mine.txt") == "the user's");
  CHECK(names(dir + "/result/sub") == std::set<std::string>{"new.txt", "old.txt"});
  // A failed re-run leaves the previous result as it was.
  {
    OutputFolder out(dir + "/result");
    write_text(out.file("a.txt"), "failed a");
  }
  CHECK(read_text(dir + "/result/a.txt") == "new a");
  CHECK(names(dir) == std::set<std::string>{"result"});
}

TEST_CASE("OutputFolder in place: a rollback removes what the run added and keeps what was there") {
  const std::string dir = scratch("in_place");
  fs::create_directories(dir + "/study");
  write_text(dir + "/study/rows.csv", "row 1\n");
  {
    OutputFolder out(dir + "/study", "out", OutputFolder::Mode::InPlace);
    CHECK(fs::equivalent(out.path(), dir + "/study"));
    write_text(out.file("rows.csv"), "row 1\nrow 2\n");  // resumed: appended rows
    write_text(out.file("study.json"), "{}");
  }
  CHECK(names(dir + "/study") == std::set<std::string>{"rows.csv"});
  CHECK(read_text(dir + "/study/rows.csv") == "row 1\nrow 2\n");
  {
    OutputFolder out(dir + "/new/study", "out", OutputFolder::Mode::InPlace);
    write_text(out.file("rows.csv"), "row\n");
  }
  CHECK(names(dir) == std::set<std::string>{"study"});
  {
    OutputFolder out(dir + "/new/study", "out", OutputFolder::Mode::InPlace);
    write_text(out.file("rows.csv"), "row\n");
    out.commit();
  }
  CHECK(read_text(dir + "/new/study/rows.csv") == "row\n");
}

TEST_CASE("Output paths are checked before anything is written, with the parameter named") {
  const std::string dir = scratch("checks");
  write_text(dir + "/file.txt", "x");
  std::string parameter;
  CHECK(io_error([&] { OutputFolder out(dir + "/file.txt", "out"); }, &parameter).find("is an existing file") !=
        std::string::npos);
  CHECK(parameter == "out");
  CHECK(io_error([&] { OutputFolder out(dir + "/file.txt/sub"); }).find("which is a file, not a folder") !=
        std::string::npos);
  CHECK(io_error([&] { OutputFolder out("/dev/null"); }).find("special file") != std::string::npos);
  CHECK(io_error([&] { OutputFolder out(""); }).find("empty") != std::string::npos);
  CHECK(io_error([&] { OutputFolder out("/proc/corrlap_output"); }).find("/proc") != std::string::npos);
  CHECK(io_error([&] { StagedFile out(dir, "volume_out"); }, &parameter).find("is an existing folder") !=
        std::string::npos);
  CHECK(parameter == "volume_out");
  CHECK(io_error([&] { StagedFile out(dir + "/file.txt/x.obj"); }).find("which is a file") != std::string::npos);
  CHECK(io_error([&] { StagedFile out(dir + "/missing/x.obj"); }).find("does not exist") != std::string::npos);
  CHECK(io_error([&] { StagedFile out("/proc/corrlap_output.obj"); }).find("/proc") != std::string::npos);
  CHECK(names(dir) == std::set<std::string>{"file.txt"});
}

TEST_CASE("StagedFile: renamed onto the destination at commit, removed without, special files in place") {
  const std::string dir = scratch("staged_file");
  write_text(dir + "/x.vol", "old");
  {
    StagedFile out(dir + "/x.vol");
    CHECK(fs::path(out.path()).extension() == ".vol");  // the writers choose the format by it
    write_text(out.path(), "new");
    CHECK(read_text(dir + "/x.vol") == "old");
  }
  CHECK(names(dir) == std::set<std::string>{"x.vol"});
  CHECK(read_text(dir + "/x.vol") == "old");
  {
    StagedFile out(dir + "/x.vol");
    write_text(out.path(), "new");
    out.commit();
  }
  CHECK(names(dir) == std::set<std::string>{"x.vol"});
  CHECK(read_text(dir + "/x.vol") == "new");
  StagedFile null("/dev/null");
  CHECK(null.path() == "/dev/null");
  null.commit();
  CHECK(fs::is_character_file("/dev/null"));
}
