// The rules for the files the program reads and writes (files.h): inputs
// that could block or are too large are refused before a byte is read;
// outputs never replace a link, a device or an input, and a run's outputs
// reach their directory together.
#include "files.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <gtest/gtest.h>

#include "temp_dir.h"

namespace {

std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

TEST(Files, AFifoWithoutAWriterIsRefusedAtOnce) {
  TempDir dir;
  const std::string fifo = dir.path() + "/fifo";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  std::string err, bytes;
  EXPECT_EQ(OpenInput(fifo, 100, &err), -1);  // returns: the open does not block
  EXPECT_EQ(err, "not a regular file");
  EXPECT_FALSE(ReadInput("/dev/zero", 100, &bytes, &err));
  EXPECT_EQ(err, "/dev/zero: not a regular file");
  EXPECT_FALSE(ReadInput(dir.path(), 100, &bytes, &err));
  EXPECT_EQ(err, dir.path() + ": not a regular file");
}

TEST(Files, TheSizeBoundIsCheckedBeforeReading) {
  TempDir dir;
  const std::string path = dir.Write("f", std::string(101, 'x'));
  std::string err, bytes;
  EXPECT_FALSE(ReadInput(path, 100, &bytes, &err));
  EXPECT_EQ(err, path + ": 101 bytes, more than the limit of 100 bytes");
  EXPECT_TRUE(bytes.empty());
  ASSERT_TRUE(ReadInput(path, 101, &bytes, &err)) << err;
  EXPECT_EQ(bytes.size(), 101u);
  EXPECT_FALSE(ReadInput(path, 64, &bytes, &err));
  EXPECT_EQ(err, path + ": 101 bytes, more than the limit of 64 bytes");
}

TEST(Files, OutputsNeverReplaceInputsLinksOrDevices) {
  TempDir dir;
  std::vector<Input> inputs;
  std::string err;
  const std::string scene = dir.Write("scene.obj", "v 0 0 0\n");
  ASSERT_TRUE(AddInput("the scene", scene, &inputs, &err)) << err;
  EXPECT_EQ(Unwritable(scene, inputs), "is the scene");
  const std::string hard = dir.path() + "/hard";
  ASSERT_EQ(link(scene.c_str(), hard.c_str()), 0);
  EXPECT_EQ(Unwritable(hard, inputs), "is the scene (" + scene + ")");
  const std::string soft = dir.path() + "/soft";
  ASSERT_EQ(symlink(scene.c_str(), soft.c_str()), 0);
  EXPECT_EQ(Unwritable(soft, inputs), "is a symbolic link");
  EXPECT_EQ(Unwritable("/dev/null", inputs), "is not a regular file");
  EXPECT_EQ(Unwritable(dir.path(), inputs), "is not a regular file");
  EXPECT_EQ(Unwritable(dir.path() + "/new", inputs), "");
  EXPECT_EQ(Unwritable(dir.Write("old", "x"), inputs), "");
  EXPECT_FALSE(WriteFileAtomic(soft, "new", &err));
  EXPECT_EQ(err, soft + ": is a symbolic link; not replaced");
  EXPECT_EQ(Slurp(scene), "v 0 0 0\n");
}

TEST(Files, AtomicWritesLeaveNothingBeside) {
  TempDir dir;
  std::string err;
  const std::string path = dir.path() + "/out";
  ASSERT_TRUE(WriteFileAtomic(path, "one", &err)) << err;
  ASSERT_TRUE(WriteFileAtomic(path, "two", &err, true)) << err;
  EXPECT_EQ(Slurp(path), "two");
  struct stat st;
  ASSERT_EQ(stat(path.c_str(), &st), 0);
  const mode_t mask = umask(0);
  umask(mask);
  EXPECT_EQ(st.st_mode & 0777, 0666 & ~mask);  // not mkstemp's 0600
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()),
                          std::filesystem::directory_iterator()),
            1);
}

TEST(Files, StagedOutputsArriveTogetherAndReplaceAWholeEarlierRun) {
  TempDir dir;
  std::string err;
  dir.Write("result.csv", "old");
  dir.Write("frame-09.png", "old");
  dir.Write("notes.txt", "mine");
  auto ours = [](const std::string& n) { return n == "result.csv" || n.compare(0, 6, "frame-") == 0; };
  Staging run;
  ASSERT_TRUE(run.Open(dir.path(), &err)) << err;
  ASSERT_TRUE(WriteFileAtomic(run.Path("log.csv"), "new", &err)) << err;
  EXPECT_FALSE(std::filesystem::exists(dir.path() + "/log.csv"));  // not before Commit
  ASSERT_TRUE(run.Commit({}, ours, &err)) << err;
  EXPECT_EQ(Slurp(dir.path() + "/log.csv"), "new");
  EXPECT_FALSE(std::filesystem::exists(dir.path() + "/result.csv"));  // the earlier run's
  EXPECT_FALSE(std::filesystem::exists(dir.path() + "/frame-09.png"));
  EXPECT_EQ(Slurp(dir.path() + "/notes.txt"), "mine");
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()),
                          std::filesystem::directory_iterator()),
            2);  // the private directory is gone
}

TEST(Files, AStagedOutputOntoAnInputMovesNothing) {
  TempDir dir;
  std::string err;
  std::vector<Input> inputs;
  const std::string ref = dir.Write("result.csv", "reference");
  ASSERT_TRUE(AddInput("the --reference file", ref, &inputs, &err));
  Staging run;
  ASSERT_TRUE(run.Open(dir.path(), &err)) << err;
  ASSERT_TRUE(WriteFileAtomic(run.Path("result.csv"), "new", &err)) << err;
  ASSERT_TRUE(WriteFileAtomic(run.Path("log.csv"), "new", &err)) << err;
  EXPECT_FALSE(run.Commit(inputs, [](const std::string&) { return true; }, &err));
  EXPECT_EQ(err.substr(0, ref.size() + 26), ref + ": is the --reference file;");
  EXPECT_EQ(Slurp(ref), "reference");
  EXPECT_FALSE(std::filesystem::exists(dir.path() + "/log.csv"));
}

}  // namespace
