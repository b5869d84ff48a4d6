// The install layout: what a program reads at run time is found relative to the program itself.
#include "hattr/core/install_layout.hpp"

#include <filesystem>

#include <gtest/gtest.h>

namespace hattr {
namespace {

TEST(InstallLayout, TheCodeIsInThisTestProgram) {
  EXPECT_EQ(std::filesystem::canonical(codeLocation()), std::filesystem::canonical("/proc/self/exe"));
}

TEST(InstallLayout, PrefixesAreTheProgramsFoldersNearestFirstThenTheConfiguredPrefix) {
  const auto prefixes = candidatePrefixes();
  ASSERT_GE(prefixes.size(), 3u);
  EXPECT_EQ(prefixes.front(), codeLocation().parent_path());
  EXPECT_EQ(prefixes[1], codeLocation().parent_path().parent_path());
  EXPECT_EQ(prefixes[prefixes.size() - 2], std::filesystem::path("/")) << "every ancestor up to the root";
  EXPECT_TRUE(prefixes.back().is_absolute()) << "the configured install prefix comes last";
}

TEST(InstallLayout, TheBuildFolderIsAPrefixWithTheStagedDataAndPlugins) {
  // This program is in BUILD/tests/; the build stages BUILD/share/hattr and BUILD/LIBDIR/hattr/plugins.
  const auto build = codeLocation().parent_path().parent_path();
  const auto share = findShareDir();
  ASSERT_TRUE(share.has_value()) << "looked in " << searchedShareDirs();
  EXPECT_EQ(*share, build / relativeShareDir());
  EXPECT_TRUE(std::filesystem::is_regular_file(*share / "glyphs" / "na.json"));
  EXPECT_TRUE(std::filesystem::is_regular_file(*share / "sim" / "trainee_model.json"));
  const auto plugins = findPluginDir();
  ASSERT_TRUE(plugins.has_value());
  EXPECT_EQ(*plugins, build / relativePluginDir());
  EXPECT_EQ(relativeShareDir().filename(), "hattr");
  EXPECT_EQ(relativePluginDir().filename(), "plugins");
}

TEST(InstallLayout, TheSearchedPlacesAreNamedForAnErrorMessage) {
  const std::string searched = searchedShareDirs();
  EXPECT_NE(searched.find((codeLocation().parent_path() / relativeShareDir()).string()), std::string::npos) << searched;
}

}  // namespace
}  // namespace hattr
