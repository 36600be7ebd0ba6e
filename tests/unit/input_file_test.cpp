// Reading the files the firmware and the tools are given (drivers/input_file.hpp): only regular
// files, size-capped before a byte is read, never blocking on a FIFO or a device; the TOML nesting
// check that keeps toml++'s recursion bounded; paths that must stay inside a dataset folder.
#include "harmoloc/drivers/input_file.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>

#include "test_support.hpp"

namespace hd = harmoloc::drivers;
namespace ht = harmoloc::test;
namespace fs = std::filesystem;

TEST(InputFile, ReadsARegularFileWhole) {
  ht::TempDir dir;
  const std::string path = dir.write("a.txt", std::string(100000, 'x') + "end");
  std::string text;
  EXPECT_EQ(hd::read_regular_file(path, 200000, text), "");
  EXPECT_EQ(text.size(), 100003U);
  EXPECT_EQ(text.substr(text.size() - 3), "end");
  EXPECT_EQ(hd::read_regular_file(dir.write("empty", ""), 10, text), "");
  EXPECT_TRUE(text.empty());
  // Exactly at the cap is fine.
  EXPECT_EQ(hd::read_regular_file(dir.write("ten", "0123456789"), 10, text), "");
  EXPECT_EQ(text, "0123456789");
}

TEST(InputFile, RefusesWhatIsNotARegularFileWithoutBlocking) {
  ht::TempDir dir;
  std::string text = "stale";
  EXPECT_EQ(hd::read_regular_file(dir.dir(), 1000, text), "not a regular file (a directory)");
  EXPECT_TRUE(text.empty());
  EXPECT_EQ(hd::read_regular_file("/dev/zero", 1000, text),
            "not a regular file (a character device)");
  // A FIFO without a writer: a plain open for reading would wait for one forever.
  const std::string fifo = dir.path("fifo");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(hd::read_regular_file(fifo, 1000, text), "not a regular file (a FIFO)");
  const char* why = nullptr;
  EXPECT_EQ(hd::open_regular_file(fifo.c_str(), &why), -1);
  EXPECT_STREQ(why, "not a regular file (a FIFO)");
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(2));
  const std::string missing = hd::read_regular_file(dir.path("nope"), 1000, text);
  EXPECT_EQ(missing.rfind("cannot open (", 0), 0U) << missing;
  // A regular file opens, and its descriptor is non-blocking.
  const int fd = hd::open_regular_file(dir.write("ok", "x").c_str(), &why);
  ASSERT_GE(fd, 0) << why;
  EXPECT_NE(::fcntl(fd, F_GETFL) & O_NONBLOCK, 0);
  ::close(fd);
}

TEST(InputFile, ChecksTheSizeBeforeReading) {
  // A 300 MB (sparse) file against a 1 MB cap: refused from its size, nothing read.
  ht::TempDir dir;
  const std::string path = dir.path("big");
  {
    const int fd = ::open(path.c_str(), O_CREAT | O_WRONLY, 0600);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::ftruncate(fd, 300L * 1000 * 1000), 0);
    ::close(fd);
  }
  std::string text;
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(hd::read_regular_file(path, 1U << 20, text),
            "300000000 bytes, more than the 1048576 this file may have");
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::milliseconds(500));
  EXPECT_TRUE(text.empty());
  EXPECT_LT(text.capacity(), 1U << 20);
  // One byte over.
  EXPECT_NE(hd::read_regular_file(dir.write("eleven", "01234567890"), 10, text), "");
}

TEST(InputFile, TomlNestingIsBounded) {
  // The probe's config: 50,000 dotted-key parts (100 KB) overflowed toml++'s stack.
  std::string deep;
  for (int i = 0; i < 50000; ++i) deep += "a.";
  deep += "a = 1\n";
  const std::string e = hd::check_toml_nesting(deep);
  EXPECT_EQ(e,
            "line 1: nested 50001 deep (dotted keys, tables and arrays), more than the 32 allowed");

  // What counts: header parts + dotted key parts + inline tables and arrays around a value.
  EXPECT_EQ(hd::check_toml_nesting("[a.b.c]\nd.e = 1\n", 5), "");
  EXPECT_NE(hd::check_toml_nesting("[a.b.c]\nd.e = 1\n", 4), "");
  EXPECT_EQ(hd::check_toml_nesting("[[a.b]]\nc = [[1, 2], [3]]\n", 5), "");
  EXPECT_NE(hd::check_toml_nesting("[[a.b]]\nc = [[1, 2], [3]]\n", 4), "");
  EXPECT_EQ(hd::check_toml_nesting("x = {a = {b = {c.d = 1}}}\n", 5), "");  // x.a.b.c.d
  EXPECT_NE(hd::check_toml_nesting("x = {a = {b = {c.d = 1}}}\n", 4), "");
  EXPECT_EQ(hd::check_toml_nesting("a = [{b = [1]}]\n", 4), "");  // a, [], b, []
  EXPECT_NE(hd::check_toml_nesting("a = [{b = [1]}]\n", 3), "");
  EXPECT_NE(hd::check_toml_nesting("x = " + std::string(40, '[') + std::string(40, ']') + "\n"),
            "");
  EXPECT_NE(hd::check_toml_nesting("[" + deep.substr(0, 200) + "a]\n"), "");
  // A later line names itself.
  EXPECT_EQ(hd::check_toml_nesting("a = 1\n\nb.c.d.e = 2\n", 3).rfind("line 3: ", 0), 0U);
  // The header stops counting at the next one.
  EXPECT_EQ(hd::check_toml_nesting("[a.b.c]\nx = 1\n[d]\ne.f = 2\n", 4), "");

  // Not counted: dots and brackets in strings, comments, numbers, multi-line strings.
  EXPECT_EQ(hd::check_toml_nesting("\"a.b.c.d.e\" = 1.5\n", 1), "");
  EXPECT_EQ(hd::check_toml_nesting("a = 'x.y.z[[[{{{'\n", 1), "");
  EXPECT_EQ(hd::check_toml_nesting("a = 1 # b.c.d.e [[[[[\n", 1), "");
  EXPECT_EQ(hd::check_toml_nesting("a = [1.5, 2.5, 3.5, 4.5, 5.5, 6.5]\n", 2), "");
  EXPECT_EQ(hd::check_toml_nesting("a = \"\"\"\nb.c.d = [[[[\n\\\"\"\"\"\"\nx = 1\n", 1), "");
  EXPECT_EQ(hd::check_toml_nesting("a = '''\nb.c.d = [[[['''\nx = 1\n", 1), "");
  EXPECT_EQ(hd::check_toml_nesting("a = \"q\\\"[[[[[\"\n", 1), "");
  // A newline inside an array keeps its depth (arrays may span lines).
  EXPECT_NE(hd::check_toml_nesting("a = [\n[\n[\n1]]]\n", 3), "");
  EXPECT_EQ(hd::check_toml_nesting("a = [\n[\n[\n1]]]\n", 4), "");
}

TEST(InputFile, TheShippedTomlFilesPass) {
  for (const char* name : {"docs/examples/harmoloc.toml"}) {
    std::string text;
    const std::string path = std::string(HARMOLOC_SOURCE_DIR) + "/" + name;
    ASSERT_EQ(hd::read_regular_file(path, hd::input_limits::kTomlBytes, text), "") << path;
    EXPECT_EQ(hd::check_toml_nesting(text), "") << path;
  }
}

TEST(InputFile, PathsStayInsideTheirFolder) {
  ht::TempDir dir;
  const std::string data = dir.mkdir("data");
  dir.mkdir("data/frames");
  dir.write("outside.csv", "x");
  EXPECT_EQ(hd::check_inside(data, "frames.csv"), "");
  EXPECT_EQ(hd::check_inside(data, "frames/000001.ppm"), "");
  EXPECT_EQ(hd::check_inside(data, "./frames/./x"), "");
  EXPECT_NE(hd::check_inside(data, "../outside.csv"), "");
  EXPECT_NE(hd::check_inside(data, "frames/../../outside.csv"), "");
  EXPECT_NE(hd::check_inside(data, dir.path("outside.csv")), "");
  EXPECT_NE(hd::check_inside(data, "/dev/zero"), "");
  EXPECT_NE(hd::check_inside(data, ""), "");
  // A symbolic link the dataset holds is followed (datasets share frames that way), but what it
  // leads to is read only if it is a regular file.
  fs::create_symlink(dir.path("outside.csv"), dir.path("data/link.csv"));
  fs::create_directory_symlink("/dev", dir.path("data/devices"));
  EXPECT_EQ(hd::check_inside(data, "link.csv"), "");
  std::string text;
  EXPECT_EQ(hd::read_regular_file(dir.path("data/link.csv"), 10, text), "");
  EXPECT_EQ(hd::read_regular_file(dir.path("data/devices/zero"), 10, text),
            "not a regular file (a character device)");
}
