#include "server/daemon_config.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace nephele {
namespace {

using ::testing::HasSubstr;

const std::string kScene =
    "scene = \"" + std::string(NEPHELE_SOURCE_DIR) + "/config/scenes/cirrus.toml\"\n";

TEST(DaemonConfig, DefaultsAndTheExample) {
  DaemonConfig c;
  ASSERT_EQ(parseDaemonConfig(kScene, "t.toml", c), "");
  EXPECT_EQ(c.mode, TickMode::kRealtime);
  EXPECT_EQ(c.socket.bind, "127.0.0.1");
  EXPECT_EQ(c.modbus.bind, "127.0.0.1");
  ASSERT_EQ(c.views.size(), 1u);
  EXPECT_EQ(c.views[0].camera.width, 1280);  // the scene's camera
  EXPECT_EQ(c.modbus_view, c.views[0].name);
  EXPECT_EQ(c.socket_timeouts.request_s, 10.0);
  EXPECT_EQ(c.socket_timeouts.idle_s, 300.0);
  EXPECT_EQ(c.modbus_timeouts.request_s, 2.0);
  EXPECT_EQ(c.max_ellipsoids, defaultMaxEllipsoids());
  EXPECT_GE(c.max_ellipsoids, 65536);
  EXPECT_TRUE(c.prewarm);
  DaemonConfig cold;
  ASSERT_EQ(parseDaemonConfig(kScene + "[world]\nprewarm = false\n", "t.toml", cold), "");
  EXPECT_FALSE(cold.prewarm);

  DaemonConfig example;
  ASSERT_EQ(loadDaemonConfig(std::string(NEPHELE_SOURCE_DIR) + "/deploy/nephele.toml", example),
            "");
  EXPECT_EQ(example.views.size(), 2u);
  EXPECT_EQ(example.views[1].image.format, ImageFormat::kPng);
  EXPECT_FALSE(example.views[1].image.coverage);
  EXPECT_EQ(example.snapshotDirectory(), "/var/lib/nephele");
  for (const char* other :
       {"/config/daemon.toml", "/deploy/docker.toml", "/deploy/cockpit/left.toml"}) {
    DaemonConfig c;
    const std::string error = loadDaemonConfig(std::string(NEPHELE_SOURCE_DIR) + other, c);
    // docker.toml names the scene where the image puts it, so only that error is allowed.
    if (std::string(other) == "/deploy/docker.toml")
      EXPECT_THAT(error, HasSubstr("scenes/cumulus.toml")) << other;
    else
      EXPECT_EQ(error, "") << other;
  }
}

TEST(DaemonConfig, ErrorsNameTheKey) {
  struct Case {
    std::string text;
    const char* words;
  };
  const Case cases[] = {
      {"[world]\nmode = \"realtime\"\n", "missing key scene"},
      {"scene = \"/nonexistent.toml\"\n", "cannot read scene file"},
      {kScene + "[world]\nmode = \"fast\"\n", "world.mode: \"fast\" is not allowed"},
      {kScene + "[world]\ntick_rate = 0\n", "world.tick_rate"},
      {kScene + "[cigi]\nrecentre_distance = 10\n", "recentre_distance: is below 1000 m"},
      {kScene + "[[stream]]\nview = \"front\"\n", "missing key address"},
      {kScene + "[[stream]]\nview = \"back\"\naddress = \"udp://127.0.0.1:5600\"\n",
       "\"back\" is not a [[view]]"},
      {kScene +
           "[[view]]\nname = \"front\"\n[[stream]]\nview = \"front\"\naddress = \"http://x:1\"\n",
       "address: \"http://x:1\" (allowed: udp://"},
      {kScene +
           "[[view]]\nname = \"front\"\n[[stream]]\nview = \"front\"\naddress = \"udp://x:1\"\n"
           "bitrate = 50\n",
       "bitrate"},
      {kScene + "[[view]]\nwidth = 10\n", "missing key name"},
      {kScene + "[[view]]\nname = \"a\"\n[[view]]\nname = \"a\"\n", "names two views"},
      {kScene + "[[view]]\nname = \"a\"\nformat = \"jpeg\"\ncoverage = true\n", "jpeg"},
      {kScene + "[modbus]\nview = \"rear\"\n", "modbus.view: \"rear\" is not a view"},
      {kScene + "[modbus]\nallow = [1]\n", "modbus.allow"},
      {kScene + "[socket]\nport = 70000\n", "socket.port"},
      {kScene + "[socket]\nmystery = 1\n", "socket.mystery: unknown key"},
      {kScene + "[output]\nformat = \"raw\"\n", "output.format"},
      {kScene + "[socket]\nrequest_timeout = 0\n", "socket.request_timeout"},
      {kScene + "[modbus]\nidle_timeout = -1\n", "modbus.idle_timeout"},
      {kScene + "[[view]]\nname = \"front view\"\n", "is not a name"},
      {"scene = \"/tmp\"\n", "not a regular file"},
      {kScene + "[world]\nmax_ellipsoids = 0\n", "world.max_ellipsoids"},
      {kScene + "[world]\nprewarm = 1\n", "world.prewarm"},
      // The world budget holds for the scene too: cumulus.toml's heap has 27 lobes.
      {"scene = \"" + std::string(NEPHELE_SOURCE_DIR) +
           "/config/scenes/cumulus.toml\"\n[world]\nmax_ellipsoids = 26\n",
       "more than the world's budget of 26 ([world] max_ellipsoids)"},
  };
  for (const Case& c : cases) {
    DaemonConfig out;
    EXPECT_THAT(parseDaemonConfig(c.text, "t.toml", out), HasSubstr(c.words)) << c.text;
  }
}

}  // namespace
}  // namespace nephele
