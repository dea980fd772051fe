// Plugin loading: the real volumes plugin, and every way a plugin file can
// be wrong, each reported with its reason.

#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "app/ModuleManager.h"
#include "app/Session.h"
#include "TestPaths.h"

namespace fs = std::filesystem;

namespace {

fs::path testPlugin(const char* name)
{
  return fs::path(CAPS_TEST_PLUGIN_DIR) / (std::string("libcaps_test_") + name + ".so");
}

} // namespace

TEST(ModuleManager, LoadsTheVolumesPluginFromItsFile)
{
  caps::ModuleManager manager;
  manager.loadFolder(CAPS_MODULE_DIR);
  const caps::Module* volumes = manager.find("volumes");
  ASSERT_NE(volumes, nullptr) << manager.report();
  EXPECT_EQ(volumes->title(), "Volumes");
  EXPECT_NE(manager.findCommand("info").second, nullptr);
  EXPECT_EQ(manager.findCommand("info").first, volumes);
  EXPECT_EQ(manager.findCommand("no-such-command").second, nullptr);
  EXPECT_NE(manager.report().find("libcaps_module_volumes.so"), std::string::npos);
  EXPECT_TRUE(manager.failures().empty()) << manager.report();
}

// The Report module adds File > Export (plain, de-identified, with the
// convergence study), File > Print and File > Export thickness report to the
// workstation.
TEST(ModuleManager, TheReportModuleAddsExportAndPrintToTheFileMenu)
{
  caps::ModuleManager manager;
  manager.loadFolder(CAPS_MODULE_DIR);
  const caps::Module* report = manager.find("report");
  ASSERT_NE(report, nullptr) << manager.report();
  std::vector<std::string> titles;
  for (const auto& action : report->actions())
  {
    EXPECT_EQ(action.menu, "File");
    EXPECT_TRUE(bool(action.run)) << action.title;
    titles.push_back(action.title);
  }
  ASSERT_EQ(titles.size(), 5u);
  EXPECT_EQ(titles[0], "Export plan report as &PDF...");
  EXPECT_EQ(titles[2], "Export plan report with &convergence study as PDF...");
  EXPECT_EQ(titles[3], "&Print plan report...");
  EXPECT_EQ(titles[4], "Export &thickness report as PDF...");
  EXPECT_NE(manager.findCommand("report").second, nullptr);
}

TEST(ModuleManager, ReportsEveryBadPluginWithItsReason)
{
  const fs::path folder = caps::test::scratchFolder();
  fs::copy_file(testPlugin("probe_module"), folder / "a_probe.so");
  fs::copy_file(testPlugin("probe_module"), folder / "b_probe_again.so");
  fs::copy_file(testPlugin("not_a_module"), folder / "c_not_a_module.so");
  fs::copy_file(testPlugin("wrong_api_module"), folder / "d_wrong_api.so");
  std::ofstream(folder / "e_text.so") << "this is text, not a library\n";
  fs::copy_file(testPlugin("other_build_module"), folder / "f_other_build.so");
  std::ofstream(folder / "readme.txt") << "ignored: not a .so\n";

  caps::ModuleManager manager;
  manager.loadFolder(folder);
  ASSERT_EQ(manager.modules().size(), 1u) << manager.report();
  EXPECT_EQ(manager.modules()[0].module->name(), "probe");
  ASSERT_EQ(manager.failures().size(), 5u) << manager.report();
  const auto reason = [&](const char* file) {
    for (const auto& f : manager.failures())
      if (f.file.filename() == file)
        return f.reason;
    return std::string("(not reported)");
  };
  EXPECT_NE(reason("b_probe_again.so").find("repeats module 'probe'"), std::string::npos);
  EXPECT_NE(reason("c_not_a_module.so").find("is not a CAPS module"), std::string::npos);
  EXPECT_NE(reason("d_wrong_api.so").find("rebuild the module"), std::string::npos);
  EXPECT_NE(reason("e_text.so").find("cannot be loaded"), std::string::npos);
  // The right API from other sources: refused before any of its code runs,
  // naming both builds and what to do.
  const std::string other = reason("f_other_build.so");
  EXPECT_NE(other.find("was built from other sources (build 0.0.0+0123456789abcdef, this caps is " +
                       std::string(caps::buildStamp()) + ")"),
            std::string::npos)
    << other;
  EXPECT_NE(other.find("rebuild it with this caps"), std::string::npos) << other;
}

// Every plugin of the build carries the app's own stamp, and the stamp says
// which version and which sources: "VERSION+16 hex digits".
TEST(ModuleManager, ThePluginsOfThisBuildCarryItsStamp)
{
  const std::string stamp = caps::buildStamp();
  EXPECT_EQ(stamp.rfind(std::string(CAPS_VERSION) + "+", 0), 0u) << stamp;
  const std::string hash = stamp.substr(stamp.find('+') + 1);
  EXPECT_EQ(hash.size(), 16u) << stamp;
  EXPECT_EQ(hash.find_first_not_of("0123456789abcdef"), std::string::npos) << stamp;
  caps::ModuleManager manager;
  manager.loadFolder(CAPS_MODULE_DIR);
  EXPECT_GE(manager.modules().size(), 8u) << manager.report();
  EXPECT_TRUE(manager.failures().empty()) << manager.report();
}

TEST(ModuleManager, CommandsRunOnTheSessionsLogic)
{
  const fs::path folder = caps::test::scratchFolder();
  fs::copy_file(testPlugin("probe_module"), folder / "probe.so");
  caps::ModuleManager manager;
  manager.loadFolder(folder);
  auto [module, command] = manager.findCommand("probe");
  ASSERT_NE(command, nullptr);
  caps::Session session(manager);
  std::ostringstream out, err;
  EXPECT_EQ(command->run(session.logic(*module), {"x", "y"}, out, err), 7);
  EXPECT_EQ(out.str(), "nodes=0 args=2");
  // The logic is made once per session.
  EXPECT_EQ(&session.logic(*module), &session.logic(*module));
}

TEST(ModuleManager, MissingFolderIsNotAnError)
{
  caps::ModuleManager manager;
  manager.loadFolder("/no/such/plugin/folder");
  EXPECT_TRUE(manager.modules().empty());
  EXPECT_TRUE(manager.failures().empty());
  EXPECT_NE(manager.report().find("/no/such/plugin/folder"), std::string::npos);
}
