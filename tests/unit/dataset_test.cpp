// Dataset formats: TUM trajectories, the frame index and PPM headers, candump logs, metadata.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/dataset/candump_log.hpp"
#include "harmoloc/dataset/encoder_csv.hpp"
#include "harmoloc/dataset/frame_index.hpp"
#include "harmoloc/dataset/metadata.hpp"
#include "harmoloc/dataset/tum.hpp"
#include "test_support.hpp"

namespace hd = harmoloc::dataset;
namespace ha = harmoloc::algorithms;
namespace ht = harmoloc::test;
using ha::kPi;

namespace {

// The message is one line that starts with "<file>:<line>: ".
void expect_file_line_error(const std::string& msg, const std::string& file, int line) {
  ht::expect_one_line(msg, file + ":" + std::to_string(line) + ": ");
}

}  // namespace

// --- TUM -------------------------------------------------------------------------------------

TEST(Tum, YawFromQuaternion) {
  for (double yaw : {0.0, 0.3, -1.2, kPi / 2.0, 3.0, -3.1, kPi - 1e-9}) {
    EXPECT_NEAR(ha::wrap_angle_rad(
                    hd::yaw_from_quaternion(0, 0, std::sin(yaw / 2), std::cos(yaw / 2)) - yaw),
                0.0, 1e-12)
        << yaw;
    // q and -q are the same rotation.
    EXPECT_NEAR(ha::wrap_angle_rad(
                    hd::yaw_from_quaternion(0, 0, -std::sin(yaw / 2), -std::cos(yaw / 2)) - yaw),
                0.0, 1e-12);
  }
  // Yaw of q = qz(a) * qx(b): a roll of b about the body x axis does not change the heading a.
  const double a = 0.8, b = 0.3;
  const double cz = std::cos(a / 2), sz = std::sin(a / 2), cx = std::cos(b / 2),
               sx = std::sin(b / 2);
  // (cz + sz k)(cx + sx i) = cz cx + cz sx i + sz cx k + sz sx (k i = j)
  EXPECT_NEAR(hd::yaw_from_quaternion(cz * sx, sz * sx, sz * cx, cz * cx), a, 1e-12);
}

TEST(Tum, WriteReadRoundTrip) {
  ht::TempDir dir;
  std::vector<hd::StampedPose> poses;
  for (int i = 0; i < 50; ++i) {
    hd::StampedPose p;
    p.t_s = 1767225600.0 + 0.033333 * i;
    p.pose = ha::Pose2{0.1 * i - 1.0, 2.0 - 0.05 * i, ha::wrap_angle_rad(0.3 * i)};
    poses.push_back(p);
  }
  const std::string path = dir.path("t.tum");
  hd::write_tum(path, poses);
  const std::vector<hd::StampedPose> back = hd::read_tum(path);
  ASSERT_EQ(back.size(), poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    EXPECT_NEAR(back[i].t_s, poses[i].t_s, 1e-6);
    EXPECT_NEAR(back[i].pose.x_m, poses[i].pose.x_m, 1e-6);
    EXPECT_NEAR(back[i].pose.y_m, poses[i].pose.y_m, 1e-6);
    EXPECT_NEAR(ha::wrap_angle_rad(back[i].pose.yaw_rad - poses[i].pose.yaw_rad), 0.0, 1e-8) << i;
  }
  // The line format: t x y 0 0 0 qz qw.
  char line[160];
  const int n = hd::format_tum_line(line, sizeof line, 12.5, ha::Pose2{1.0, -2.0, kPi / 2.0});
  EXPECT_EQ(std::string(line, static_cast<std::size_t>(n)),
            "12.500000 1.000000 -2.000000 0 0 0 0.707106781 0.707106781\n");
}

TEST(Tum, CommentsAndBlankLinesAreSkipped) {
  ht::TempDir dir;
  const std::string path =
      dir.write("t.tum", "# t x y z qx qy qz qw\n\n1.0 1 2 0 0 0 0 1\n   \n2.0 3 4 0 0 0 1 0\n");
  const auto poses = hd::read_tum(path);
  ASSERT_EQ(poses.size(), 2U);
  EXPECT_DOUBLE_EQ(poses[1].pose.x_m, 3.0);
  EXPECT_NEAR(std::fabs(poses[1].pose.yaw_rad), kPi, 1e-12);
}

TEST(Tum, MalformedLinesNameFileAndLine) {
  ht::TempDir dir;
  const std::string ok = "# header\n1.0 0 0 0 0 0 0 1\n";
  struct Case {
    const char* name;
    std::string body;
    int line;
  };
  const Case cases[] = {
      {"seven", "2.0 0 0 0 0 0 1\n", 3},
      {"nan", "2.0 nan 0 0 0 0 0 1\n", 3},
      {"inf", "2.0 1e999 0 0 0 0 0 1\n", 3},
      {"nine", "2.0 0 0 0 0 0 0 1 7\n", 3},
      {"text", "2.0 0 0 zero 0 0 0 1\n", 3},
      {"same", "1.0 0 0 0 0 0 0 1\n", 3},
      {"back", "2.0 0 0 0 0 0 0 1\n\n0.5 0 0 0 0 0 0 1\n", 5},
  };
  for (const Case& c : cases) {
    const std::string p = dir.write(std::string(c.name) + ".tum", ok + c.body);
    expect_file_line_error(ht::error_of([&] { hd::read_tum(p); }), p, c.line);
  }
  EXPECT_NE(ht::error_of([&] { hd::read_tum(dir.path("missing.tum")); }).find("missing.tum"),
            std::string::npos);
}

TEST(Tum, InterpolateAcrossPlusMinusPi) {
  std::vector<hd::StampedPose> t(3);
  t[0].t_s = 10.0;
  t[0].pose = ha::Pose2{0.0, 0.0, 3.0};
  t[1].t_s = 11.0;
  t[1].pose = ha::Pose2{1.0, 2.0, -3.0};  // 0.283 rad further on, through pi
  t[2].t_s = 13.0;
  t[2].pose = ha::Pose2{3.0, 2.0, -2.0};
  ha::Pose2 p;
  ASSERT_TRUE(hd::interpolate(t, 10.5, p));
  EXPECT_NEAR(p.x_m, 0.5, 1e-12);
  EXPECT_NEAR(p.y_m, 1.0, 1e-12);
  EXPECT_NEAR(ha::wrap_angle_rad(p.yaw_rad - kPi), 0.0, 1e-12);  // halfway: pi, not 0
  ASSERT_TRUE(hd::interpolate(t, 10.25, p));
  EXPECT_NEAR(ha::wrap_angle_rad(p.yaw_rad - (3.0 + 0.25 * (2.0 * kPi - 6.0))), 0.0, 1e-12);
  ASSERT_TRUE(hd::interpolate(t, 12.0, p));
  EXPECT_NEAR(p.x_m, 2.0, 1e-12);
  EXPECT_NEAR(p.yaw_rad, -2.5, 1e-12);
  // The ends are inside; outside is refused.
  ASSERT_TRUE(hd::interpolate(t, 10.0, p));
  EXPECT_NEAR(p.yaw_rad, 3.0, 1e-12);
  ASSERT_TRUE(hd::interpolate(t, 13.0, p));
  EXPECT_NEAR(p.x_m, 3.0, 1e-12);
  EXPECT_FALSE(hd::interpolate(t, 9.999, p));
  EXPECT_FALSE(hd::interpolate(t, 13.001, p));
  EXPECT_FALSE(hd::interpolate({}, 1.0, p));
}

// --- frames.csv and PPM ----------------------------------------------------------------------

TEST(FrameIndex, ParsesHeaderAndLines) {
  ht::TempDir dir;
  const std::string p =
      dir.write("frames.csv",
                "timestamp_ns,file\n1000,frames/000000.ppm\r\n2000,frames/000001.ppm\n\n"
                "9999999999999999999,frames/last.ppm\n");
  const auto frames = hd::read_frame_index(p);
  ASSERT_EQ(frames.size(), 3U);
  EXPECT_EQ(frames[0].timestamp_ns, 1000U);
  EXPECT_EQ(frames[0].file, "frames/000000.ppm");
  EXPECT_EQ(frames[1].file, "frames/000001.ppm");             // CR stripped
  EXPECT_EQ(frames[2].timestamp_ns, 9999999999999999999ULL);  // 19 digits
  // Write and read back.
  const std::string q = dir.path("copy.csv");
  hd::write_frame_index(q, frames);
  const auto again = hd::read_frame_index(q);
  ASSERT_EQ(again.size(), frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(again[i].timestamp_ns, frames[i].timestamp_ns);
    EXPECT_EQ(again[i].file, frames[i].file);
  }
}

TEST(FrameIndex, RejectsBadLinesWithFileAndLine) {
  ht::TempDir dir;
  const std::string head = "timestamp_ns,file\n1000,a.ppm\n";
  struct Case {
    const char* name;
    std::string body;
    int line;
  };
  const Case cases[] = {
      {"stamp", "12a0,b.ppm\n", 3},
      {"negative", "-5,b.ppm\n", 3},
      {"float", "1.5e3,b.ppm\n", 3},
      {"empty_stamp", ",b.ppm\n", 3},
      {"no_comma", "2000 b.ppm\n", 3},
      {"empty_file", "2000,\n", 3},
      {"dotdot", "2000,../outside.ppm\n", 3},
      {"dotdot_inner", "2000,frames/../../x.ppm\n", 3},
      {"absolute", "2000,/etc/passwd\n", 3},
      {"same_time", "1000,b.ppm\n", 3},
      {"backwards", "2000,b.ppm\n1500,c.ppm\n", 4},
      {"too_big", "99999999999999999999,b.ppm\n", 3},
  };
  for (const Case& c : cases) {
    const std::string p = dir.write(std::string(c.name) + ".csv", head + c.body);
    expect_file_line_error(ht::error_of([&] { hd::read_frame_index(p); }), p, c.line);
  }
}

TEST(Ppm, ParseHeaderVariants) {
  auto parse = [](const std::string& s, hd::PpmHeader& h, const char** why) {
    return hd::parse_ppm_header(reinterpret_cast<const std::uint8_t*>(s.data()), s.size(), h, why);
  };
  hd::PpmHeader h;
  const char* why = nullptr;
  std::string s = "P6\n4 3\n255\n";
  ASSERT_TRUE(parse(s + "pixels", h, &why));
  EXPECT_EQ(h.width_px, 4U);
  EXPECT_EQ(h.height_px, 3U);
  EXPECT_EQ(h.data_offset, s.size());
  s = "P6\n# made by hand\n# two comments\n640 480 # trailing comment\n255\n";
  ASSERT_TRUE(parse(s + "x", h, &why)) << why;
  EXPECT_EQ(h.width_px, 640U);
  EXPECT_EQ(h.height_px, 480U);
  EXPECT_EQ(h.data_offset, s.size());
  s = "P6 2 2 255 ";  // single spaces are whitespace too
  ASSERT_TRUE(parse(s + "abcdefghijkl", h, &why));
  EXPECT_EQ(h.data_offset, s.size());
  // The pixel data may start with a byte that looks like whitespace or a digit.
  s = "P6\n1 1\n255\n";
  ASSERT_TRUE(parse(s + "\n9#", h, &why));
  EXPECT_EQ(h.data_offset, s.size());

  why = nullptr;
  EXPECT_FALSE(parse("P6\n4 3\n65535\n", h, &why));
  ASSERT_NE(why, nullptr);
  EXPECT_NE(std::string(why).find("maxval"), std::string::npos) << why;
  why = nullptr;
  EXPECT_FALSE(parse("P5\n4 3\n255\n", h, &why));
  ASSERT_NE(why, nullptr);
  EXPECT_NE(std::string(why).find("P6"), std::string::npos) << why;
  for (const char* truncated : {"", "P", "P6", "P6\n", "P6\n4", "P6\n4 3", "P6\n4 3\n",
                                "P6\n4 3\n255", "P6\n# only a comment"}) {
    why = nullptr;
    EXPECT_FALSE(parse(truncated, h, &why)) << "'" << truncated << "'";
    EXPECT_NE(why, nullptr);
  }
  EXPECT_FALSE(parse("P6\n0 3\n255\n", h, &why));
  EXPECT_FALSE(parse("P6\n4 -3\n255\n", h, &why));
  EXPECT_FALSE(parse("P6\n99999999999 3\n255\n", h, &why));
  EXPECT_FALSE(parse("P6\n4 3\n255x", h, &why));
  EXPECT_FALSE(parse("P3\n4 3\n255\n", h, &why));
  EXPECT_FALSE(parse("P5\n4 3\n255\n", h, nullptr));  // a null reason pointer is allowed
}

TEST(Ppm, WriteThenParseRoundTrip) {
  ht::TempDir dir;
  const std::uint32_t w = 5, h = 4;
  std::vector<std::uint8_t> rgb(w * h * 3);
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<std::uint8_t>(i * 13U + 10U);
  rgb[0] = '\n';  // a first pixel byte that looks like whitespace
  const std::string path = dir.path("f.ppm");
  hd::write_ppm(path, w, h, rgb.data());
  const std::vector<std::uint8_t> bytes = ht::read_bytes(path);
  hd::PpmHeader header;
  const char* why = nullptr;
  ASSERT_TRUE(hd::parse_ppm_header(bytes.data(), bytes.size(), header, &why)) << why;
  EXPECT_EQ(header.width_px, w);
  EXPECT_EQ(header.height_px, h);
  ASSERT_EQ(bytes.size(), header.data_offset + rgb.size());
  EXPECT_TRUE(std::equal(rgb.begin(), rgb.end(),
                         bytes.begin() + static_cast<std::ptrdiff_t>(header.data_offset)));
  EXPECT_THROW(hd::write_ppm(dir.path("no/such/dir/f.ppm"), w, h, rgb.data()), std::runtime_error);
}

// --- candump logs ------------------------------------------------------------------------------

TEST(Candump, ParsesStandardAndExtendedFrames) {
  ha::CanFrame f;
  std::string why;
  ASSERT_TRUE(hd::parse_candump_line("(1700000000.123456) can0 181#0011223344556677", f, why))
      << why;
  EXPECT_EQ(f.id, 0x181U);
  EXPECT_FALSE(f.extended);
  EXPECT_EQ(f.length, 8);
  for (std::uint8_t i = 0; i < 8; ++i) EXPECT_EQ(f.data[i], 0x11 * i) << int{i};
  EXPECT_EQ(f.timestamp_ns, 1700000000123456000ULL);

  ASSERT_TRUE(hd::parse_candump_line("(0000000001.000001) vcan1 18FF00a1#DeAd", f, why)) << why;
  EXPECT_EQ(f.id, 0x18FF00A1U);
  EXPECT_TRUE(f.extended);
  EXPECT_EQ(f.length, 2);
  EXPECT_EQ(f.data[0], 0xDE);
  EXPECT_EQ(f.data[1], 0xAD);
  EXPECT_EQ(f.data[2], 0);
  EXPECT_EQ(f.timestamp_ns, 1000001000ULL);

  ASSERT_TRUE(hd::parse_candump_line("(5.000000) can0 7FF#", f, why)) << why;  // no data
  EXPECT_EQ(f.id, 0x7FFU);
  EXPECT_EQ(f.length, 0);
  ASSERT_TRUE(hd::parse_candump_line("(5.000000) can0 123#0102\r", f, why)) << why;  // CRLF file
  EXPECT_EQ(f.length, 2);
}

TEST(Candump, RejectsMalformedLines) {
  const char* bad[] = {
      "1700000000.123456) can0 181#00",          // no '('
      "(1700000000.123456 can0 181#00",          // no ')'
      "(1700000000.12345) can0 181#00",          // 5-digit microseconds
      "(1700000000.1234567) can0 181#00",        // 7 digits
      "(1700000000) can0 181#00",                // no fraction
      "(.123456) can0 181#00",                   // no seconds
      "(17000x0000.123456) can0 181#00",         // non-digit
      "(1.000000) can0 181#0G",                  // bad hex in data
      "(1.000000) can0 1G1#00",                  // bad hex in ID
      "(1.000000) can0 181#001",                 // odd data length
      "(1.000000) can0 181#001122334455667788",  // 9 bytes
      "(1.000000) can0 181##10011",              // CAN FD
      "(1.000000) can0 181#R",                   // remote frame
      "(1.000000) can0 181#r",
      "(1.000000) can0 1810#00",      // 4-digit ID
      "(1.000000) can0 800#00",       // 11-bit ID out of range
      "(1.000000) can0 20000000#00",  // 29-bit ID out of range
      "(1.000000) can0 18100",        // no '#'
      "(1.000000) 181#00",            // no interface
      "",
  };
  for (const char* line : bad) {
    ha::CanFrame f;
    std::string why;
    EXPECT_FALSE(hd::parse_candump_line(line, f, why)) << "accepted: " << line;
    EXPECT_FALSE(why.empty()) << line;
  }
  ha::CanFrame f;
  std::string why;
  hd::parse_candump_line("(1.000000) can0 181##10011", f, why);
  EXPECT_NE(why.find("FD"), std::string::npos) << why;
  hd::parse_candump_line("(1.000000) can0 181#R", f, why);
  EXPECT_NE(why.find("remote"), std::string::npos) << why;
}

TEST(Candump, FormatParseRoundTrip) {
  std::uint64_t s = 5;
  auto next = [&s]() {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    return s >> 16;
  };
  for (int i = 0; i < 500; ++i) {
    ha::CanFrame f;
    f.extended = (i % 3) == 0;
    f.id = static_cast<std::uint32_t>(next() % (f.extended ? 0x20000000ULL : 0x800ULL));
    f.length = static_cast<std::uint8_t>(next() % 9);
    for (std::uint8_t k = 0; k < f.length; ++k) f.data[k] = static_cast<std::uint8_t>(next());
    f.timestamp_ns = (next() % 4000000000000000ULL) * 1000ULL;  // whole microseconds
    const std::string line = hd::format_candump_line(f, "can0");
    ha::CanFrame g;
    std::string why;
    ASSERT_TRUE(hd::parse_candump_line(line, g, why)) << line << ": " << why;
    EXPECT_EQ(g.id, f.id) << line;
    EXPECT_EQ(g.extended, f.extended) << line;
    EXPECT_EQ(g.length, f.length) << line;
    EXPECT_EQ(g.timestamp_ns, f.timestamp_ns) << line;
    for (std::uint8_t k = 0; k < 8; ++k) EXPECT_EQ(g.data[k], k < f.length ? f.data[k] : 0) << line;
  }
  ha::CanFrame f;
  f.id = 0x181;
  f.length = 2;
  f.data[0] = 0x1A;
  f.data[1] = 0x0B;
  f.timestamp_ns = 1767225600010000000ULL;
  EXPECT_EQ(hd::format_candump_line(f, "can0"), "(1767225600.010000) can0 181#1A0B");
}

TEST(Candump, ReadLogNamesFileAndLine) {
  ht::TempDir dir;
  std::string p = dir.write("ok.log", "(1.000000) can0 181#00\n\n(1.010000) can0 281#0102\n");
  const auto frames = hd::read_candump_log(p);
  ASSERT_EQ(frames.size(), 2U);
  EXPECT_EQ(frames[1].id, 0x281U);
  p = dir.write("bad.log", "(1.000000) can0 181#00\n(1.010000) can0 181#0\n");
  expect_file_line_error(ht::error_of([&] { hd::read_candump_log(p); }), p, 2);
}

// A line dated before the one above it made a 57 cm jump, and one dated ahead switched odometry
// off for the rest of the run (exit 0, no counter); both now stop start-up at FILE:LINE. Equal
// timestamps (two frames in one microsecond) are in order.
TEST(Candump, LinesOutOfTimeOrderAreRefusedAtFileAndLine) {
  ht::TempDir dir;
  std::string p = dir.write("same.log",
                            "(1.000000) can0 181#00\n(1.000000) can0 281#01\n"
                            "(1.010000) can0 181#02\n");
  EXPECT_EQ(hd::read_candump_log(p).size(), 3U);
  p = dir.write("past.log",
                "(1.000000) can0 181#00\n(1.010000) can0 181#01\n\n(0.500000) can0 181#02\n"
                "(1.020000) can0 181#03\n");
  std::string msg = ht::error_of([&] { hd::read_candump_log(p); });
  ht::expect_one_line(msg, p + ":4: ", "timestamp 0.500000 is before line 2's 1.010000");
  p = dir.write("future.log",
                "(1.000000) can0 181#00\n(99999.010000) can0 181#01\n(1.020000) can0 181#02\n"
                "(1.030000) can0 181#03\n");
  msg = ht::error_of([&] { hd::read_candump_log(p); });
  ht::expect_one_line(msg, p + ":3: ", "before line 2's 99999.010000");
}

// --- GPIO encoder recordings (encoders.csv) ---------------------------------------------------

TEST(EncoderCsv, ParsesSignedAndUnsignedCountsWithinTheWidth) {
  hd::EncoderSample s;
  const char* why = nullptr;
  auto parse = [&](const std::string& line, std::uint8_t bits) {
    why = nullptr;
    return hd::parse_encoder_csv_line(line.data(), line.size(), bits, s, &why);
  };
  ASSERT_TRUE(parse("1767225600033333333,27,4294967295", 32)) << why;
  EXPECT_EQ(s.timestamp_ns, 1767225600033333333ULL);
  EXPECT_EQ(s.left_ticks, 27U);
  EXPECT_EQ(s.right_ticks, 4294967295U);
  ASSERT_TRUE(parse("5,-1,-2147483648\r", 32)) << why;  // signed, CRLF
  EXPECT_EQ(s.left_ticks, 0xFFFFFFFFU);
  EXPECT_EQ(s.right_ticks, 0x80000000U);
  ASSERT_TRUE(parse("18446744073709551615,65535,-32768", 16)) << why;
  EXPECT_EQ(s.timestamp_ns, 18446744073709551615ULL);
  EXPECT_EQ(s.left_ticks, 65535U);
  EXPECT_EQ(s.right_ticks, 32768U);
  ASSERT_TRUE(parse("0,-0,0000255", 8)) << why;
  EXPECT_EQ(s.left_ticks, 0U);
  EXPECT_EQ(s.right_ticks, 255U);

  const std::pair<const char*, std::uint8_t> bad[] = {
      {"", 32},
      {"1,2", 32},      // two fields
      {"1,2,3,4", 32},  // four
      {"1,2,3,", 32},   // a trailing comma
      {" 1,2,3", 32},   // spaces
      {"1, 2,3", 32},
      {"+1,2,3", 32},  // signs on the timestamp
      {"-1,2,3", 32},
      {"1.5,2,3", 32},  // not whole
      {"1e3,2,3", 32},
      {"18446744073709551616,2,3", 32},  // 2^64 ns
      {"1,4294967296,3", 32},            // 2^32
      {"1,-2147483649,3", 32},           // below -2^31
      {"1,65536,3", 16},
      {"1,-32769,3", 16},
      {"1,256,0", 8},
      {"1,2,-", 32},  // a sign alone
      {"1,,3", 32},
      {"1,0x10,3", 32},
      {"1,2,3\r\r", 32},
      {"1,2,3", 7},  // a width the firmware does not have
      {"1,2,3", 33},
  };
  for (const auto& [line, bits] : bad) {
    EXPECT_FALSE(parse(line, bits)) << "accepted: '" << line << "' at " << int{bits} << " bits";
    EXPECT_NE(why, nullptr) << line;
  }
}

TEST(EncoderCsv, FormatParseRoundTrip) {
  std::uint64_t r = 11;
  auto next = [&r]() {
    r = r * 6364136223846793005ULL + 1442695040888963407ULL;
    return r;
  };
  char buf[64];
  for (int i = 0; i < 2000; ++i) {
    const std::uint8_t bits = static_cast<std::uint8_t>(8 + i % 25);
    const std::uint32_t mask = bits == 32 ? 0xFFFFFFFFU : (1U << bits) - 1U;
    const hd::EncoderSample s{next(), static_cast<std::uint32_t>(next() >> 7) & mask,
                              static_cast<std::uint32_t>(next() >> 11) & mask};
    const std::size_t n = hd::format_encoder_csv_line(s, buf, sizeof buf);
    ASSERT_GT(n, 0U);
    ASSERT_EQ(buf[n - 1], '\n');
    hd::EncoderSample back;
    const char* why = nullptr;
    ASSERT_TRUE(hd::parse_encoder_csv_line(buf, n - 1, bits, back, &why)) << buf << why;
    EXPECT_EQ(back, s) << buf;
  }
  EXPECT_EQ(hd::format_encoder_csv_line(hd::EncoderSample{1, 2, 3}, buf, 5), 0U);  // too small
  hd::format_encoder_csv_line(hd::EncoderSample{1767225600000000000ULL, 0, 4294967295U}, buf,
                              sizeof buf);
  EXPECT_STREQ(buf, "1767225600000000000,0,4294967295\n");
}

TEST(EncoderCsv, ReadNamesFileAndLine) {
  ht::TempDir dir;
  const std::string header = std::string(hd::kEncoderCsvHeader) + "\n";
  std::string p = dir.write("ok.csv", header + "100,1,2\n200,-1,3\n300,5,6");  // no final newline
  const auto samples = hd::read_encoder_csv(p, 16);
  ASSERT_EQ(samples.size(), 3U);
  EXPECT_EQ(samples[1], (hd::EncoderSample{200, 65535, 3}));
  EXPECT_EQ(samples[2], (hd::EncoderSample{300, 5, 6}));
  p = dir.write("crlf.csv", std::string(hd::kEncoderCsvHeader) + "\r\n100,1,2\r\n");
  EXPECT_EQ(hd::read_encoder_csv(p, 32).size(), 1U);

  struct Case {
    std::string text;
    int line;
    const char* what;
  };
  const Case bad[] = {
      {"", 1, "header"},
      {"timestamp_ns,left,right\n1,2,3\n", 1, "header"},
      {"# a comment\n" + header + "1,2,3\n", 1, "header"},
      {header + "100,1,2\n100,1,2\n", 3, "not after"},  // repeated timestamp
      {header + "200,1,2\n100,1,2\n", 3, "not after"},  // going back
      {header + "100,1,2\n\n200,1,2\n", 3, "empty"},    // a blank line inside
      {header + "100,1,2\n\n", 3, "empty"},             // two newlines at the end
      {header + "100,1,2\n200,1,70000\n", 3, "width"},  // beyond 16 bits
      {header + "100;1;2\n", 2, "three fields"},
  };
  for (const Case& c : bad) {
    p = dir.write("bad.csv", c.text);
    const std::string msg = ht::error_of([&] { hd::read_encoder_csv(p, 16); });
    ht::expect_one_line(msg, p + ":" + std::to_string(c.line) + ": ", c.what);
  }
  p = dir.write("empty.csv", header);
  ht::expect_one_line(ht::error_of([&] { hd::read_encoder_csv(p, 16); }), p + ": ", "no samples");
  ht::expect_one_line(ht::error_of([&] { hd::read_encoder_csv(dir.path("none.csv"), 16); }),
                      dir.path("none.csv") + ": ", "cannot open");
}

// --- metadata.toml -----------------------------------------------------------------------------

namespace {
// The least a metadata.toml must hold (rate_hz last of its table, for tests that add camera keys).
const std::string kMinimalMetadata =
    "format_version = 1\n[camera]\nwidth_px = 160\nheight_px = 120\nrate_hz = 30\n"
    "[robot]\nwheel_radius_m = 0.05\ntrack_m = 0.3\nticks_per_rev = 4096\n";
}  // namespace

TEST(Metadata, WriteReadRoundTrip) {
  ht::TempDir dir;
  hd::DatasetMetadata m;
  m.name = "unit";
  m.image_width_px = 320;
  m.image_height_px = 240;
  m.pixel_format = harmoloc::hal::PixelFormat::kYuyv;
  m.frame_rate_hz = 15.0;
  m.frames_index = "idx.csv";
  m.encoder_log = "bus.log";
  m.ground_truth = "gt.tum";
  m.can_interface = "can1";
  m.geometry.wheel_radius_m = 0.0625;
  m.geometry.track_m = 0.42;
  m.geometry.ticks_per_rev = 16384;
  m.geometry.left_direction = -1;
  m.encoder_layout.id = 0x18FF0001;
  m.encoder_layout.length = 4;
  m.encoder_layout.left_offset = 2;
  m.encoder_layout.right_offset = 0;
  m.encoder_layout.counter_bits = 16;
  m.encoder_layout.byte_order = ha::ByteOrder::kBigEndian;
  m.seed = 1234;
  hd::write_metadata(dir.dir(), m);
  const hd::DatasetMetadata r = hd::read_metadata(dir.dir());
  EXPECT_EQ(r.name, "unit");
  EXPECT_EQ(r.image_width_px, 320U);
  EXPECT_EQ(r.image_height_px, 240U);
  EXPECT_EQ(r.pixel_format, harmoloc::hal::PixelFormat::kYuyv);
  EXPECT_DOUBLE_EQ(r.frame_rate_hz, 15.0);
  EXPECT_EQ(r.frames_index, "idx.csv");
  EXPECT_EQ(r.encoder_log, "bus.log");
  EXPECT_EQ(r.ground_truth, "gt.tum");
  EXPECT_EQ(r.can_interface, "can1");
  EXPECT_DOUBLE_EQ(r.geometry.wheel_radius_m, 0.0625);
  EXPECT_DOUBLE_EQ(r.geometry.track_m, 0.42);
  EXPECT_DOUBLE_EQ(r.geometry.ticks_per_rev, 16384.0);
  EXPECT_EQ(r.geometry.left_direction, -1);
  EXPECT_EQ(r.geometry.right_direction, 1);
  EXPECT_EQ(r.encoder_layout.id, 0x18FF0001U);
  EXPECT_EQ(r.encoder_layout.length, 4);
  EXPECT_EQ(r.encoder_layout.left_offset, 2);
  EXPECT_EQ(r.encoder_layout.right_offset, 0);
  EXPECT_EQ(r.encoder_layout.counter_bits, 16);
  EXPECT_EQ(r.encoder_layout.byte_order, ha::ByteOrder::kBigEndian);
  EXPECT_EQ(r.seed, 1234U);

  EXPECT_EQ(r.encoder_source, hd::EncoderSource::kCan);

  // No ground truth: the key is left out and reads back empty.
  m.ground_truth.clear();
  hd::write_metadata(dir.dir(), m);
  EXPECT_EQ(hd::read_metadata(dir.dir()).ground_truth, "");
  // A CAN dataset's metadata does not mention the source (files written before it existed
  // stay byte for byte the same); a GPIO recording's does.
  const std::vector<std::uint8_t> written = ht::read_bytes(dir.path("metadata.toml"));
  EXPECT_EQ(std::string(written.begin(), written.end()).find("source"), std::string::npos);
  m.encoder_source = hd::EncoderSource::kGpio;
  m.encoder_log = "encoders.csv";
  hd::write_metadata(dir.dir(), m);
  EXPECT_EQ(hd::read_metadata(dir.dir()).encoder_source, hd::EncoderSource::kGpio);
  EXPECT_EQ(hd::read_metadata(dir.dir()).encoder_log, "encoders.csv");
}

TEST(Metadata, EncoderSourceSelectsTheRecordingAndItsDefaultFile) {
  ht::TempDir dir;
  const std::string base = kMinimalMetadata;
  dir.write("metadata.toml", base);
  hd::DatasetMetadata m = hd::read_metadata(dir.dir());
  EXPECT_EQ(m.encoder_source, hd::EncoderSource::kCan);
  EXPECT_EQ(m.encoder_log, "encoders.log");
  dir.write("metadata.toml", base + "[encoders]\nsource = \"gpio\"\ncounter_bits = 16\n");
  m = hd::read_metadata(dir.dir());
  EXPECT_EQ(m.encoder_source, hd::EncoderSource::kGpio);
  EXPECT_EQ(m.encoder_log, "encoders.csv");
  EXPECT_EQ(m.encoder_layout.counter_bits, 16);
  dir.write("metadata.toml", base + "[encoders]\nsource = \"quadrature\"\n");
  ht::expect_one_line(ht::error_of([&] { hd::read_metadata(dir.dir()); }),
                      "metadata.toml: ", "encoders.source");
}

// camera.forward_offset_m is optional (the trainer then maps bearings from the axle's place):
// absent it reads NaN and is not written; given it reads back; beyond 1 m it is refused.
TEST(Metadata, CameraOffsetIsOptional) {
  ht::TempDir dir;
  const std::string base = kMinimalMetadata;
  dir.write("metadata.toml", base);
  hd::DatasetMetadata m = hd::read_metadata(dir.dir());
  EXPECT_TRUE(std::isnan(m.camera_forward_m));
  hd::write_metadata(dir.dir(), m);
  const std::vector<std::uint8_t> plain = ht::read_bytes(dir.path("metadata.toml"));
  EXPECT_EQ(std::string(plain.begin(), plain.end()).find("forward_offset_m"), std::string::npos);
  m.camera_forward_m = 0.125;
  hd::write_metadata(dir.dir(), m);
  EXPECT_DOUBLE_EQ(hd::read_metadata(dir.dir()).camera_forward_m, 0.125);
  std::string far = base;
  far.insert(far.find("rate_hz"), "forward_offset_m = 1.5\n");
  dir.write("metadata.toml", far);
  ht::expect_one_line(ht::error_of([&] { hd::read_metadata(dir.dir()); }),
                      "metadata.toml: ", "camera.forward_offset_m");
}

// camera.height_m is optional too (the trainer's geometry fit needs it, else takes
// --camera-height-m): absent NaN and not written; given it reads back; 0 or beyond 5 m refused.
TEST(Metadata, CameraHeightIsOptional) {
  ht::TempDir dir;
  const std::string base = kMinimalMetadata;
  dir.write("metadata.toml", base);
  hd::DatasetMetadata m = hd::read_metadata(dir.dir());
  EXPECT_TRUE(std::isnan(m.camera_height_m));
  hd::write_metadata(dir.dir(), m);
  const std::vector<std::uint8_t> plain = ht::read_bytes(dir.path("metadata.toml"));
  EXPECT_EQ(std::string(plain.begin(), plain.end()).find("height_m"), std::string::npos);
  m.camera_height_m = 0.355;
  hd::write_metadata(dir.dir(), m);
  EXPECT_DOUBLE_EQ(hd::read_metadata(dir.dir()).camera_height_m, 0.355);
  for (const char* bad : {"height_m = 0\n", "height_m = 7.5\n", "height_m = \"low\"\n"}) {
    std::string text = base;
    text.insert(text.find("rate_hz"), bad);
    dir.write("metadata.toml", text);
    ht::expect_one_line(ht::error_of([&] { hd::read_metadata(dir.dir()); }),
                        "metadata.toml: ", "camera.height_m");
  }
}

TEST(Metadata, CalibratedGeometryKeepsItsPrecision) {
  // A calibrated robot's numbers (and an NTSC frame rate) must survive write -> read: the host
  // board takes the odometry geometry from the metadata when the config has no [odometry].
  ht::TempDir dir;
  hd::DatasetMetadata m;
  m.image_width_px = 160;
  m.image_height_px = 120;
  m.frame_rate_hz = 30000.0 / 1001.0;
  m.geometry.wheel_radius_m = 0.0498731;
  m.geometry.track_m = 0.3012345;
  m.geometry.ticks_per_rev = 4096.0 * 4.0 * 19.2;  // 314572.8
  hd::write_metadata(dir.dir(), m);
  const hd::DatasetMetadata r = hd::read_metadata(dir.dir());
  EXPECT_NEAR(r.geometry.wheel_radius_m, m.geometry.wheel_radius_m, 1e-12);
  EXPECT_NEAR(r.geometry.track_m, m.geometry.track_m, 1e-12);
  EXPECT_NEAR(r.geometry.ticks_per_rev, m.geometry.ticks_per_rev, 1e-9);
  EXPECT_NEAR(r.frame_rate_hz, m.frame_rate_hz, 1e-9);
}

TEST(Metadata, ErrorsStartWithMetadataToml) {
  ht::TempDir dir;
  auto msg_for = [&](const std::string& text) {
    dir.write("metadata.toml", text);
    return ht::error_of([&] { hd::read_metadata(dir.dir()); });
  };
  auto expect_meta_error = [](const std::string& msg, const std::string& what) {
    ht::expect_one_line(msg, "metadata.toml: ", what);
  };
  // Missing file.
  expect_meta_error(ht::error_of([&] { hd::read_metadata(dir.path("nothing-here")); }),
                    "not found");
  const std::string good = kMinimalMetadata;
  dir.write("metadata.toml", good);
  EXPECT_NO_THROW(hd::read_metadata(dir.dir()));
  expect_meta_error(msg_for("format_version = 2\n" + good.substr(good.find('\n') + 1)),
                    "format_version");
  expect_meta_error(msg_for(good.substr(good.find('\n') + 1)), "format_version");
  std::string bad_format = good;
  bad_format.insert(bad_format.find("rate_hz"), "pixel_format = \"bgr24\"\n");
  expect_meta_error(msg_for(bad_format), "pixel_format");
  std::string odd_yuyv = good;
  odd_yuyv.replace(odd_yuyv.find("width_px = 160"), 14, "width_px = 161\npixel_format = \"yuyv\"");
  expect_meta_error(msg_for(odd_yuyv), "even");
  std::string no_width = good;
  no_width.erase(no_width.find("width_px = 160\n"), 15);
  expect_meta_error(msg_for(no_width), "camera.width_px");
  std::string zero_radius = good;
  zero_radius.replace(zero_radius.find("0.05"), 4, "0.0");
  expect_meta_error(msg_for(zero_radius), "robot.wheel_radius_m");
  expect_meta_error(msg_for(good + "[encoders]\nlength = 4\n"),
                    "encoders");  // 2 x 32 bits in 4 bytes
  expect_meta_error(msg_for(good + "[encoders]\nbyte_order = \"pdp\"\n"), "byte_order");
  expect_meta_error(msg_for("format_version = 1\n[camera\n"), "line 2");
  // Another type than an integer (a huge float was undefined behaviour in toml++'s conversion).
  const std::string rest = good.substr(good.find('\n') + 1);
  expect_meta_error(msg_for("format_version = 2.01e57\n" + rest), "format_version");
  expect_meta_error(msg_for("format_version = 1.0\n" + rest), "format_version");
  expect_meta_error(msg_for("seed = 1e300\n" + good), "seed");
  expect_meta_error(msg_for("name = 3\n" + good), "name");
}

// The files the metadata names stay inside the dataset folder: before, frames_index and
// [encoders] log could name /dev/zero (start-up grew to gigabytes) or a FIFO (start-up blocked).
TEST(Metadata, NamedFilesStayInsideTheDataset) {
  ht::TempDir dir;
  const std::string good = kMinimalMetadata;
  const std::string data = dir.mkdir("data");
  const auto error_for = [&](const std::string& section, const std::string& key,
                             const std::string& value) {
    std::string text = good;
    const std::string line = key + " = \"" + value + "\"\n";
    if (section == "camera")
      text.insert(text.find("rate_hz"), line);
    else
      text += "[" + section + "]\n" + line;
    dir.write("data/metadata.toml", text);
    return ht::error_of([&] { hd::read_metadata(data); });
  };
  for (const std::string bad : {"../secret.csv", "/dev/zero", "frames/../../secret.csv"}) {
    ht::expect_one_line(error_for("camera", "frames_index", bad),
                        "metadata.toml: ", "camera.frames_index");
    ht::expect_one_line(error_for("encoders", "log", bad), "metadata.toml: ", "encoders.log");
    ht::expect_one_line(error_for("ground_truth", "file", bad),
                        "metadata.toml: ", "ground_truth.file");
  }
  EXPECT_EQ(error_for("camera", "frames_index", "index/frames.csv"), ht::kNoException);
}

// metadata.toml itself: a folder, a FIFO or a deep TOML stops with one line (the 50,000-part
// dotted key overflowed toml++'s stack).
TEST(Metadata, NotARegularFileOrTooDeepIsRefused) {
  ht::TempDir dir;
  dir.mkdir("folder/metadata.toml");
  ht::expect_one_line(ht::error_of([&] { hd::read_metadata(dir.path("folder")); }),
                      "metadata.toml: ", "not a regular file (a directory)");
  dir.mkdir("fifo");
  ASSERT_EQ(::mkfifo(dir.path("fifo/metadata.toml").c_str(), 0600), 0);
  ht::expect_one_line(ht::error_of([&] { hd::read_metadata(dir.path("fifo")); }),
                      "metadata.toml: ", "not a regular file (a FIFO)");
  std::string deep;
  for (int i = 0; i < 50000; ++i) deep += "a.";
  dir.write("metadata.toml", deep + "a = 1\n");
  ht::expect_one_line(ht::error_of([&] { hd::read_metadata(dir.dir()); }),
                      "metadata.toml: ", "line 1: nested 50001 deep");
}
