#include "core/file_io.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>

#include "tests/test_util.h"

namespace foresight {
namespace {

namespace fs = std::filesystem;

TEST(FileIo, WritesAtomicallyAndLeavesNoTemporary) {
  testing::TempDir dir;
  const std::string path = dir.File("a.txt");
  WriteFileAtomically(path, "first");
  WriteFileAtomically(path, "second");
  EXPECT_EQ(testing::ReadText(path), "second");
  EXPECT_FALSE(fs::exists(path + ".tmp"));
}

// Issue 18: an atomic write renames over its target, so a device (e.g. `-o /dev/full`) or a
// directory given as the output would be replaced. Refused, naming the path, and left as it was.
TEST(FileIo, RefusesToReplaceSomethingThatIsNotARegularFile) {
  testing::TempDir dir;
  const std::string sub = dir.File("sub");
  fs::create_directories(sub);
  testing::ExpectErrorContains([&] { WriteFileAtomically(sub, "x"); },
                               {"sub", "not a regular file"});
  EXPECT_TRUE(fs::is_directory(sub));
  EXPECT_FALSE(fs::exists(sub + ".tmp"));
  // A FIFO stands in for a device (never touch the real ones: a regression would replace them).
  const std::string fifo = dir.File("fifo");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  testing::ExpectErrorContains([&] { WriteFileAtomically(fifo, "x"); },
                               {"fifo", "not a regular file"});
  EXPECT_TRUE(fs::is_fifo(fifo));
}

// A symbolic link to a file is written through: the file it points to gets the new contents and
// the link stays a link (a results file linked from elsewhere keeps working).
TEST(FileIo, WritesThroughASymbolicLink) {
  testing::TempDir dir;
  const std::string target = dir.File("real.txt"), link = dir.File("link.txt");
  WriteFileAtomically(target, "old");
  fs::create_symlink(target, link);
  WriteFileAtomically(link, "new");
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(link)));
  EXPECT_EQ(testing::ReadText(target), "new");
  EXPECT_EQ(testing::ReadText(link), "new");
  // A relative link is resolved against the link's folder.
  fs::create_directories(dir.File("sub"));
  const std::string rel = dir.File("sub/rel.txt");
  fs::create_symlink("../real.txt", rel);
  WriteFileAtomically(rel, "relative");
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(rel)));
  EXPECT_EQ(testing::ReadText(target), "relative");
  // A dangling link creates the file it names.
  const std::string dangling = dir.File("dangling.txt"), absent = dir.File("absent.txt");
  fs::create_symlink(absent, dangling);
  WriteFileAtomically(dangling, "made");
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dangling)));
  EXPECT_EQ(testing::ReadText(absent), "made");
}

}  // namespace
}  // namespace foresight
