#include "core/util/path_confinement.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <string>

namespace gdvr {
namespace {

namespace fs = std::filesystem;

class PathConfinementTest : public ::testing::Test {
 protected:
  void SetUp() override {
    base_ = fs::temp_directory_path() / ("gdvr_confinement_" + std::to_string(::getpid()));
    fs::remove_all(base_);
    root_ = base_ / "assets";
    fs::create_directories(root_ / "scenes");
    fs::create_directories(base_ / "assets2");
    std::ofstream(root_ / "scenes" / "a.xml") << "<scene/>";
    std::ofstream(base_ / "secret.txt") << "x";
  }
  void TearDown() override { fs::remove_all(base_); }
  fs::path base_, root_;
};

TEST_F(PathConfinementTest, FilesAndFoldersUnderTheRootAreInside) {
  EXPECT_TRUE(is_inside_root(root_ / "scenes" / "a.xml", root_));
  EXPECT_TRUE(is_inside_root(root_ / "scenes", root_));
  EXPECT_TRUE(is_inside_root(root_, root_));
  EXPECT_TRUE(is_inside_root(root_ / "not" / "there" / "yet.obj", root_));  // need not exist
  EXPECT_TRUE(is_inside_root(root_ / "scenes" / ".." / "scenes" / "a.xml", root_));
  // Trailing separators on either side change nothing.
  EXPECT_TRUE(is_inside_root(root_ / "scenes" / "a.xml", root_.string() + "/"));
  EXPECT_TRUE(is_inside_root(root_.string() + "/scenes/", root_));
}

TEST_F(PathConfinementTest, EscapesAreOutside) {
  EXPECT_FALSE(is_inside_root(root_ / ".." / "secret.txt", root_));
  EXPECT_FALSE(is_inside_root(root_ / "scenes" / ".." / ".." / "secret.txt", root_));
  EXPECT_FALSE(is_inside_root(base_ / "secret.txt", root_));
  EXPECT_FALSE(is_inside_root("/etc/passwd", root_));
  // A sibling whose name starts with the root's is not inside it.
  EXPECT_FALSE(is_inside_root(base_ / "assets2" / "x.obj", root_));
}

TEST_F(PathConfinementTest, SymlinksAreFollowed) {
  std::error_code ec;
  fs::create_symlink(base_ / "secret.txt", root_ / "link_out.txt", ec);
  ASSERT_FALSE(ec) << ec.message();
  fs::create_directory_symlink(root_ / "scenes", base_ / "link_in", ec);
  ASSERT_FALSE(ec) << ec.message();
  EXPECT_FALSE(is_inside_root(root_ / "link_out.txt", root_));
  EXPECT_TRUE(is_inside_root(base_ / "link_in" / "a.xml", root_));
}

TEST_F(PathConfinementTest, RelativePathsResolveAgainstTheWorkingFolder) {
  const fs::path cwd = fs::current_path();
  fs::current_path(root_);
  const bool inside = is_inside_root("scenes/a.xml", root_);
  const bool outside = is_inside_root("../secret.txt", root_);
  const bool relative_root = is_inside_root(root_ / "scenes" / "a.xml", ".");
  fs::current_path(cwd);
  EXPECT_TRUE(inside);
  EXPECT_FALSE(outside);
  EXPECT_TRUE(relative_root);
}

TEST_F(PathConfinementTest, UnresolvablePathsAreNotInside) {
  EXPECT_FALSE(is_inside_root("", root_));
  EXPECT_FALSE(is_inside_root(root_ / "a.xml", ""));
  // A name longer than any file system allows cannot be resolved.
  EXPECT_FALSE(is_inside_root(root_ / std::string(5000, 'a'), root_));
}

}  // namespace
}  // namespace gdvr
