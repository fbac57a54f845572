#include "shimmer/core/atomic_file.h"

#include <gtest/gtest.h>

#include <sys/resource.h>

#include <csignal>
#include <fstream>
#include <set>

#include "temp_dir.h"

namespace shimmer {
namespace {

std::string Read(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

TEST(AtomicFile, WritesReplacesAndLeavesNoTemporary) {
  testing::TempDir dir;
  ASSERT_TRUE(WriteFileAtomic(dir / "a.txt", "one"));
  ASSERT_TRUE(WriteFileAtomic(dir / "a.txt", "two"));
  EXPECT_EQ(Read(dir / "a.txt"), "two");
  EXPECT_EQ(dir.Names(), std::vector<std::string>{"a.txt"});
}

TEST(AtomicFile, TemporaryNamesAreHiddenUniqueAndKeepTheExtension) {
  std::set<std::string> names;
  for (int i = 0; i < 100; ++i) {
    const auto p = TemporaryPathFor("out/plot.png");
    EXPECT_EQ(p.parent_path(), "out");
    EXPECT_EQ(p.filename().string().front(), '.');
    EXPECT_EQ(p.extension(), ".png");
    names.insert(p.string());
  }
  EXPECT_EQ(names.size(), 100u);
}

// A failed write names the file and the system's reason, never "Success",
// and leaves neither the file nor a temporary behind.
TEST(AtomicFile, FailureNamesTheFileAndTheReason) {
  testing::TempDir dir;
  auto missing = WriteFileAtomic(dir / "no-such-dir" / "a.txt", "x");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.code(), ErrorCode::kIo);
  EXPECT_NE(missing.error().find("a.txt: cannot write (No such file or directory)"), std::string::npos)
      << missing.error();
  EXPECT_EQ(SystemReason(0, "stream failed"), "stream failed");
  EXPECT_TRUE(dir.Names().empty());
}

// A write that runs out of room (here a file-size limit, as a full disk
// would) fails with the reason, and the previous file stays as it was.
TEST(AtomicFile, RunningOutOfRoomKeepsThePreviousFile) {
  testing::TempDir dir;
  ASSERT_TRUE(WriteFileAtomic(dir / "a.txt", "old"));
  struct rlimit saved;
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &saved), 0);
  auto previous_handler = std::signal(SIGXFSZ, SIG_IGN);
  struct rlimit small = saved;
  small.rlim_cur = 1024;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  Status s = WriteFileAtomic(dir / "a.txt", std::string(64 * 1024, 'x'));
  setrlimit(RLIMIT_FSIZE, &saved);
  std::signal(SIGXFSZ, previous_handler);
  ASSERT_FALSE(s);
  EXPECT_EQ(s.code(), ErrorCode::kIo);
  EXPECT_NE(s.error().find("File too large"), std::string::npos) << s.error();
  EXPECT_EQ(Read(dir / "a.txt"), "old");
  EXPECT_EQ(dir.Names(), std::vector<std::string>{"a.txt"});
}

}  // namespace
}  // namespace shimmer
