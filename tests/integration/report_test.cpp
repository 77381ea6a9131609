// report.html as a person sees it: written by `polarslam report` over real run folders, rendered
// by headless Chromium (Debian `chromium`, installed by scripts/test). The page marks itself
// once every image has loaded; the screenshot must show the plots' colours.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "child_process.hpp"
#include "plot/image.hpp"

using namespace std::chrono_literals;
using polarslam::testing::binPath;
using polarslam::testing::ChildProcess;
using polarslam::testing::readFile;
using polarslam::testing::runToEnd;
using polarslam::testing::sourcePath;

namespace {

namespace fs = std::filesystem;

std::string findChromium() {
  for (const char* path : {"/usr/bin/chromium", "/usr/bin/chromium-browser", "/usr/bin/google-chrome"})
    if (access(path, X_OK) == 0) return path;
  return {};
}

std::vector<std::string> chromiumCommand(const std::string& chromium, const fs::path& profile) {
  return {chromium, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars", "--allow-file-access-from-files",
          "--user-data-dir=" + profile.string(), "--virtual-time-budget=10000"};
}

/// Pixels whose colour is clearly not grey: plot lines and legends, never page text or borders.
long colouredPixels(const polarslam::RgbImage& image) {
  long n = 0;
  for (const auto& p : image.pixels) n += std::max({p.r, p.g, p.b}) - std::min({p.r, p.g, p.b}) > 80 ? 1 : 0;
  return n;
}

}  // namespace

TEST(Report, RendersInHeadlessChromiumWithEveryImageLoaded) {
  const std::string chromium = findChromium();
  ASSERT_FALSE(chromium.empty()) << "headless Chromium is needed (Debian package chromium; scripts/test installs it)";
  const fs::path dir = fs::temp_directory_path() / ("polarslam-report-it-" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir / "runs");
  const std::string log = (dir / "room.lcmlog").string();
  ASSERT_EQ(runToEnd({binPath("polarslam"), "simulate", "--world", sourcePath("config/worlds/room.yaml"), "--robot",
                      sourcePath("config/robots/default.yaml"), "--seconds", "20", "-o", log},
                     dir / "simulate.out", 60s),
            0);
  for (const std::string pipeline : {"odometry", "ekf"})
    ASSERT_EQ(runToEnd({binPath("polarslam"), "run", "--log", log, "--pipeline", pipeline, "--out",
                        (dir / "runs" / pipeline).string()},
                       dir / (pipeline + ".out"), 120s),
              0)
        << readFile(dir / (pipeline + ".out"));
  ASSERT_EQ(runToEnd({binPath("polarslam"), "report", (dir / "runs").string()}, dir / "report.out", 60s), 0);
  // The page travels: copied on its own (mailed, say), it still shows every picture.
  fs::create_directories(dir / "mailed");
  fs::copy_file(dir / "runs" / "report.html", dir / "mailed" / "report.html");
  const std::string url = "file://" + (dir / "mailed" / "report.html").string();

  auto dump = chromiumCommand(chromium, dir / "profile");
  dump.insert(dump.end(), {"--dump-dom", url});
  ASSERT_EQ(runToEnd(dump, dir / "dom.html", 120s), 0) << readFile(dir / "dom.html");
  const std::string dom = readFile(dir / "dom.html");
  const std::string key = "data-images-loaded=\"";
  const size_t at = dom.find(key);
  ASSERT_NE(at, std::string::npos) << dom.substr(0, 2000);
  const size_t slash = dom.find('/', at), quote = dom.find('"', at + key.size());
  ASSERT_TRUE(slash < quote && quote != std::string::npos) << dom.substr(at, 80);
  const std::string loaded = dom.substr(at + key.size(), slash - at - key.size());
  const std::string total = dom.substr(slash + 1, quote - slash - 1);
  EXPECT_EQ(loaded, total) << "images that did not load";
  EXPECT_GE(std::stoi(total), 5) << "two trajectory plots, two error plots and the EKF's grid";

  const fs::path shot = dir / "screenshot.png";
  auto capture = chromiumCommand(chromium, dir / "profile");
  capture.insert(capture.end(), {"--window-size=1400,2400", "--screenshot=" + shot.string(), url});
  ASSERT_EQ(runToEnd(capture, dir / "screenshot.out", 120s), 0) << readFile(dir / "screenshot.out");
  const polarslam::RgbImage image = polarslam::readPng(shot.string());
  EXPECT_EQ(image.width, 1400);
  EXPECT_GT(colouredPixels(image), 3000) << "the plots' coloured lines are missing from " << shot;
  if (!HasFailure()) fs::remove_all(dir);
}
