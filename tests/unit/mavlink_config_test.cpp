// The [link] keys of the inbound side: accepted sources, the signing key file (raw or hex,
// relative to the config file, checked at start-up with one clear line) and the link id.
#include <gtest/gtest.h>

#include <string>

#include "harmoloc/firmware/config.hpp"
#include "test_support.hpp"

namespace hf = harmoloc::firmware;
namespace ht = harmoloc::test;

namespace {

void expect_error(const ht::TempDir& dir, const std::string& text, const std::string& what,
                  int line) {
  const std::string file = dir.write("harmoloc.toml", text);
  const std::string msg = ht::error_of([&] { hf::load_config(file); });
  ASSERT_NE(msg, ht::kNoException) << "accepted:\n" << text;
  ht::expect_one_line(msg, file + ": ", what);
  EXPECT_NE(msg.find("line " + std::to_string(line) + ":"), std::string::npos) << msg;
}

const char* kHexKey = "000102030405060708090a0b0c0d0e0f101112131415161718191A1B1C1D1E1F";

}  // namespace

TEST(MavlinkConfig, Defaults) {
  const hf::FirmwareConfig c = hf::default_config();
  EXPECT_EQ(c.link.accept_system_ids, std::vector<std::uint8_t>{255});
  EXPECT_EQ(c.link.accept_component_ids, std::vector<std::uint8_t>{190});
  EXPECT_FALSE(c.link.has_signing_key);
  EXPECT_TRUE(c.link.signing_key_file.empty());
  EXPECT_EQ(c.link.link_id, 0);
}

TEST(MavlinkConfig, KeysReadBack) {
  ht::TempDir dir;
  dir.write("link.key", std::string(kHexKey) + "\n");
  const std::string path = dir.write("harmoloc.toml", R"([link]
accept_system_ids = [255, 254]
accept_component_ids = []
signing_key_file = "link.key"
signing_state_file = "state/signing.state"
link_id = 7
)");
  const hf::FirmwareConfig c = hf::load_config(path);
  EXPECT_EQ(c.link.accept_system_ids, (std::vector<std::uint8_t>{255, 254}));
  EXPECT_TRUE(c.link.accept_component_ids.empty());
  EXPECT_EQ(c.link.link_id, 7);
  ASSERT_TRUE(c.link.has_signing_key);
  for (std::size_t i = 0; i < 32; ++i) EXPECT_EQ(c.link.signing_key[i], i) << i;
  EXPECT_EQ(c.link.signing_key_file, "link.key");  // as written; read from the config's folder
  EXPECT_EQ(c.link.signing_state_file, dir.path("state/signing.state"));  // from its folder
  EXPECT_EQ(c.link.signing_max_ahead_s, 60.0);
  EXPECT_FALSE(c.link.signing_peer_clock);
}

// Issue 16 item 2: with a key, the replay protection must survive a restart, so the config
// must say where it is kept; the lead a frame may have and the clock's kind are checked.
TEST(MavlinkConfig, SigningStateFileIsRequiredWithAKey) {
  ht::TempDir dir;
  dir.write("link.key", std::string(kHexKey) + "\n");
  expect_error(dir, "[link]\nsigning_key_file = \"link.key\"\n",
               "link.signing_key_file needs link.signing_state_file", 2);
  const std::string ok =
      "[link]\nsigning_key_file = \"link.key\"\nsigning_state_file = "
      "\"/var/lib/harmoloc/signing.state\"\n";
  const hf::FirmwareConfig c =
      hf::load_config(dir.write("ok.toml", ok + "signing_clock = \"peer\"\n"
                                                "signing_max_ahead_s = 5\n"));
  EXPECT_EQ(c.link.signing_state_file, "/var/lib/harmoloc/signing.state");
  EXPECT_TRUE(c.link.signing_peer_clock);
  EXPECT_EQ(c.link.signing_max_ahead_s, 5.0);
  expect_error(dir, ok + "signing_clock = \"gps\"\n", "link.signing_clock", 4);
  expect_error(dir, ok + "signing_max_ahead_s = 0\n", "link.signing_max_ahead_s", 4);
  expect_error(dir, ok + "signing_max_ahead_s = 100000\n", "link.signing_max_ahead_s", 4);
}

TEST(MavlinkConfig, RawKeyFileAndAbsolutePath) {
  ht::TempDir dir;
  std::vector<std::uint8_t> raw(32);
  for (std::size_t i = 0; i < raw.size(); ++i) raw[i] = static_cast<std::uint8_t>(255 - i);
  const std::string key = dir.write_bytes("raw.key", raw);
  const std::string path = dir.write(
      "harmoloc.toml", "[link]\nsigning_key_file = \"" + key + "\"\nsigning_state_file = \"s\"\n");
  const hf::FirmwareConfig c = hf::load_config(path);
  ASSERT_TRUE(c.link.has_signing_key);
  for (std::size_t i = 0; i < 32; ++i) EXPECT_EQ(c.link.signing_key[i], raw[i]);
}

TEST(MavlinkConfig, BadValuesStopStartUpWithOneLine) {
  ht::TempDir dir;
  expect_error(dir, "[link]\naccept_system_ids = 255\n", "link.accept_system_ids", 2);
  expect_error(dir, "[link]\naccept_system_ids = [0]\n", "link.accept_system_ids", 2);
  expect_error(dir, "[link]\n\naccept_component_ids = [1, 256]\n", "link.accept_component_ids", 3);
  expect_error(dir, "[link]\naccept_component_ids = [\"190\"]\n", "link.accept_component_ids", 2);
  expect_error(dir, "[link]\nlink_id = 256\n", "link.link_id", 2);
  expect_error(dir, "[link]\nsigning_key = \"x\"\n", "unknown key 'link.signing_key'", 2);
  expect_error(dir, "[link]\nsigning_key_file = \"missing.key\"\n", "missing.key: cannot open", 2);
  dir.write("short.key", std::string(kHexKey).substr(2) + "\n");
  expect_error(dir, "[link]\nsigning_key_file = \"short.key\"\n", "32-byte key", 2);
  dir.write("notHex.key", std::string(64, 'g'));
  expect_error(dir, "[link]\nsigning_key_file = \"notHex.key\"\n", "64 hex digits", 2);
  dir.write_bytes("zero.key", std::vector<std::uint8_t>(32, 0));
  expect_error(dir, "[link]\nsigning_key_file = \"zero.key\"\n", "all zeros", 2);
  dir.mkdir("folder.key");
  expect_error(dir, "[link]\nsigning_key_file = \"folder.key\"\n", "not a regular file", 2);
  expect_error(dir, "[link]\nsigning_key_file = \"/dev/zero\"\n", "not a regular file", 2);
}
