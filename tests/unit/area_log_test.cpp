// The area log (what a robot records for training without its frames) and the trainer that reads
// it: round trip, strict reading with one-line errors, the thresholds fingerprint, and a map
// trained from the log equal to one trained from the frames themselves.
#include "harmoloc/dataset/area_log.hpp"

#include <gtest/gtest.h>

#include <memory>

#include "harmoloc/algorithms/map_codec.hpp"
#include "harmoloc/sim_host/scenario.hpp"
#include "harmoloc/sim_host/simulate.hpp"
#include "harmoloc/sim_host/trainer.hpp"
#include "test_support.hpp"

namespace ha = harmoloc::algorithms;
namespace hs = harmoloc::sim_host;
namespace hd = harmoloc::dataset;
namespace ht = harmoloc::test;

namespace {

const std::vector<std::string> kNames{"red", "green", "blue", "yellow", "magenta", "cyan"};

std::string write_log(const ht::TempDir& dir, const std::vector<ha::AreaVector>& frames,
                      const std::vector<std::uint32_t>& distrusted = {}) {
  const std::string path = dir.path("areas.csv");
  hd::AreaLogWriter w;
  EXPECT_TRUE(w.open(path, 320, 240, ht::board_windows(), kNames));
  std::uint64_t t = 1767225600000000000ULL;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    w.write(t, frames[i], i < distrusted.size() ? distrusted[i] : 0U);
    t += 33333333;
  }
  EXPECT_TRUE(w.close());
  return path;
}

}  // namespace

TEST(AreaLog, RoundTrip) {
  ht::TempDir dir;
  std::vector<ha::AreaVector> frames(3);
  for (std::size_t i = 0; i < 3; ++i) {
    frames[i].count = 6;
    for (std::size_t k = 0; k < 6; ++k)
      frames[i].pixels[k] = static_cast<std::uint32_t>(i * 100 + k);
  }
  frames[2].pixels[5] = 320 * 240;  // the whole frame is still a valid area
  const hd::AreaLog log = hd::read_area_log(write_log(dir, frames));
  EXPECT_EQ(log.image_width_px, 320U);
  EXPECT_EQ(log.image_height_px, 240U);
  EXPECT_EQ(log.board_names, kNames);
  EXPECT_EQ(log.thresholds_crc32, hd::thresholds_fingerprint(ht::board_windows()));
  ASSERT_EQ(log.areas.size(), 3U);
  EXPECT_EQ(log.timestamp_ns[1], 1767225600033333333ULL);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(log.areas[i].count, 6U);
    for (std::size_t k = 0; k < 6; ++k) EXPECT_EQ(log.areas[i].pixels[k], frames[i].pixels[k]);
  }
}

// The trailing distrusted_mask column: written and read back; a log from before the column
// (no distrusted_mask in the header) still reads, with no distrust information.
TEST(AreaLog, DistrustedMaskRoundTripAndOldLogsStillRead) {
  ht::TempDir dir;
  std::vector<ha::AreaVector> frames(3);
  for (auto& a : frames) {
    a.count = 6;
    for (std::size_t k = 0; k < 6; ++k) a.pixels[k] = static_cast<std::uint32_t>(10 + k);
  }
  // Bits beyond the six boards are not written.
  const hd::AreaLog log = hd::read_area_log(write_log(dir, frames, {0U, 0b100101U, 0x40U | 2U}));
  EXPECT_TRUE(log.has_distrust);
  EXPECT_EQ(log.board_names, kNames);
  EXPECT_EQ(log.distrusted_mask, (std::vector<std::uint32_t>{0U, 0b100101U, 2U}));
  EXPECT_EQ(log.areas[1].pixels[5], 15U);

  const std::string old = dir.path("old.csv");
  ht::write_text(old,
                 "# harmoloc area log v1: pixels of each board per frame\n"
                 "# width_px=320 height_px=240 thresholds_crc32=0x0000abcd\n"
                 "timestamp_ns,red,green\n100,1,2\n200,3,4\n");
  const hd::AreaLog before = hd::read_area_log(old);
  EXPECT_FALSE(before.has_distrust);
  EXPECT_TRUE(before.distrusted_mask.empty());
  EXPECT_EQ(before.board_names, (std::vector<std::string>{"red", "green"}));
  ASSERT_EQ(before.areas.size(), 2U);
  EXPECT_EQ(before.areas[1].pixels[1], 4U);
}

// The columns after distrusted_mask: each board's column sum and side pixels, read back exactly;
// a frame whose columns were not measured is written with '-' and reads back unmeasured; a log
// from before the columns reads with no frame measured.
TEST(AreaLog, ColumnSumsRoundTripAndOlderLogsReadUnmeasured) {
  ht::TempDir dir;
  std::vector<ha::AreaVector> frames(3);
  for (std::size_t i = 0; i < 3; ++i) {
    ha::AreaVector& a = frames[i];
    a.count = 6;
    for (std::size_t k = 0; k < 6; ++k) {
      a.pixels[k] = static_cast<std::uint32_t>(1000 + 10 * i + k);
      a.column_sum[k] = std::uint64_t{a.pixels[k]} * (40U + 37U * k) + i;
      a.side_pixels[k] = static_cast<std::uint32_t>(k == 2 ? 480 : i);  // 480: both sides full
    }
    a.width_px = 320;
  }
  frames[1].width_px = 0;                     // not measured: written as '-'
  frames[2].column_sum[4] = 76800ULL * 319U;  // the largest sum a full frame can have
  frames[2].pixels[4] = 76800U;
  const hd::AreaLog log = hd::read_area_log(write_log(dir, frames));
  EXPECT_TRUE(log.has_columns);
  ASSERT_EQ(log.areas.size(), 3U);
  for (std::size_t i : {0U, 2U}) {
    EXPECT_EQ(log.areas[i].width_px, 320U) << i;
    EXPECT_EQ(log.areas[i].pixels, frames[i].pixels) << i;
    EXPECT_EQ(log.areas[i].column_sum, frames[i].column_sum) << i;
    EXPECT_EQ(log.areas[i].side_pixels, frames[i].side_pixels) << i;
  }
  EXPECT_FALSE(log.areas[1].columns_measured());
  EXPECT_EQ(log.areas[1].pixels, frames[1].pixels);
  EXPECT_EQ(log.areas[1].column_sum, (std::array<std::uint64_t, ha::kMaxBoards>{}));

  const std::string before = dir.path("before.csv");
  ht::write_text(before,
                 "# harmoloc area log v1: pixels of each board per frame\n"
                 "# width_px=320 height_px=240 thresholds_crc32=0x0000abcd\n"
                 "timestamp_ns,red,green,distrusted_mask\n100,1,2,0\n");
  const hd::AreaLog old = hd::read_area_log(before);
  EXPECT_TRUE(old.has_distrust);
  EXPECT_FALSE(old.has_columns);
  EXPECT_FALSE(old.areas[0].columns_measured());
}

// The row sums after the side pixels: read back exactly; a frame with columns but no rows writes
// '-' in the row fields and reads back with its columns only; a log from before the rows reads
// with columns and no rows.
TEST(AreaLog, RowSumsRoundTripAndLogsWithoutThemReadWithColumnsOnly) {
  ht::TempDir dir;
  std::vector<ha::AreaVector> frames(3);
  for (std::size_t i = 0; i < 3; ++i) {
    ha::AreaVector& a = frames[i];
    a.count = 6;
    for (std::size_t k = 0; k < 6; ++k) {
      a.pixels[k] = static_cast<std::uint32_t>(1000 + 10 * i + k);
      a.column_sum[k] = std::uint64_t{a.pixels[k]} * (40U + 37U * k);
      a.row_sum[k] = std::uint64_t{a.pixels[k]} * (20U + 31U * k) + i;
    }
    a.width_px = 320;
    a.height_px = 240;
  }
  frames[1].height_px = 0;                 // columns measured, rows not
  frames[2].row_sum[5] = 76800ULL * 239U;  // the largest sum a full frame can have
  frames[2].pixels[5] = 76800U;
  frames[2].column_sum[5] = 0;
  const hd::AreaLog log = hd::read_area_log(write_log(dir, frames));
  EXPECT_TRUE(log.has_columns);
  EXPECT_TRUE(log.has_rows);
  ASSERT_EQ(log.areas.size(), 3U);
  for (std::size_t i : {0U, 2U}) {
    EXPECT_EQ(log.areas[i].height_px, 240U) << i;
    EXPECT_TRUE(log.areas[i].rows_measured()) << i;
    EXPECT_EQ(log.areas[i].row_sum, frames[i].row_sum) << i;
    EXPECT_EQ(log.areas[i].column_sum, frames[i].column_sum) << i;
  }
  EXPECT_TRUE(log.areas[1].columns_measured());
  EXPECT_FALSE(log.areas[1].rows_measured());
  EXPECT_EQ(log.areas[1].column_sum, frames[1].column_sum);
  EXPECT_EQ(log.areas[1].row_sum, (std::array<std::uint64_t, ha::kMaxBoards>{}));
  EXPECT_DOUBLE_EQ(log.areas[0].centroid_row_px(1), 51.0);

  const std::string before = dir.path("before.csv");
  ht::write_text(before,
                 "# harmoloc area log v1: pixels of each board per frame\n"
                 "# width_px=320 height_px=240 thresholds_crc32=0x0000abcd\n"
                 "timestamp_ns,red,green,distrusted_mask,column_sum_red,column_sum_green,"
                 "side_px_red,side_px_green\n100,1,2,0,5,7,0,0\n");
  const hd::AreaLog old = hd::read_area_log(before);
  EXPECT_TRUE(old.has_columns);
  EXPECT_FALSE(old.has_rows);
  EXPECT_TRUE(old.areas[0].columns_measured());
  EXPECT_FALSE(old.areas[0].rows_measured());
  EXPECT_EQ(old.areas[0].column_sum[1], 7U);
}

TEST(AreaLog, FingerprintFollowsEveryThresholdField) {
  const ha::ThresholdSet base = ht::board_windows();
  const std::uint32_t f = hd::thresholds_fingerprint(base);
  EXPECT_EQ(f, hd::thresholds_fingerprint(ht::board_windows()));
  for (int field = 0; field < 5; ++field) {
    ha::ThresholdSet t = base;
    auto& b = t.boards[2];
    switch (field) {
      case 0:
        b.hue_min_deg += 1.0F;
        break;
      case 1:
        b.hue_max_deg -= 1.0F;
        break;
      case 2:
        b.saturation_min += 1;
        break;
      case 3:
        b.value_min += 1;
        break;
      default:
        b.value_max -= 1;
        break;
    }
    EXPECT_NE(hd::thresholds_fingerprint(t), f) << field;
  }
  EXPECT_NE(hd::thresholds_fingerprint(ht::board_windows(5)), f);
}

TEST(AreaLog, BadFilesFailWithOneLine) {
  ht::TempDir dir;
  const std::string p = dir.path("bad.csv");
  const std::string head =
      "# harmoloc area log v1: pixels of each board per frame\n"
      "# width_px=320 height_px=240 thresholds_crc32=0x0000abcd\n"
      "timestamp_ns,red,green\n";
  const std::string with_columns =
      head.substr(0, head.size() - 1) +
      ",distrusted_mask,column_sum_red,column_sum_green,side_px_red,side_px_green\n";
  const std::string with_rows =
      with_columns.substr(0, with_columns.size() - 1) + ",row_sum_red,row_sum_green\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"", "not an area log"},
      {"timestamp_ns,red\n1,2\n", "not an area log"},
      {"# harmoloc area log v1\n# width_px=0 height_px=240 thresholds_crc32=0x1\nt\n", "width_px"},
      {"# harmoloc area log v1\n# width_px=320 height_px=240 thresholds_crc32=12\nt\n",
       "hexadecimal"},
      {"# harmoloc area log v1\n# width_px=320 height_px=240 thresholds_crc32=0x1\nt,red\n",
       "timestamp_ns"},
      {"# harmoloc area log v1\n# width_px=320 height_px=240 thresholds_crc32=0x1\ntimestamp_ns\n",
       "board columns"},
      {head, "no frames"},
      {head + "100,1,2\n100,1,2\n", "increase"},
      {head + "100,1\n", "board 2"},
      {head + "100,1,2,3\n", "more columns"},
      {head + "100,1,-2\n", "board 2"},
      {head + "100,1,76801\n", "board 2"},
      {head + "1e3,1,2\n", "timestamp"},
      {head + "99999999999999999999999,1,2\n", "timestamp"},
      {"# harmoloc area log v1\n# width_px=320 height_px=240 thresholds_crc32=0x1\n"
       "timestamp_ns,distrusted_mask\n",
       "board columns"},
      {head.substr(0, head.size() - 1) + ",distrusted_mask\n100,1,2\n", "distrusted_mask"},
      {head.substr(0, head.size() - 1) + ",distrusted_mask\n100,1,2,4\n", "distrusted_mask"},
      {head.substr(0, head.size() - 1) + ",distrusted_mask\n100,1,2,x\n", "distrusted_mask"},
      {head.substr(0, head.size() - 1) + ",distrusted_mask\n100,1,2,3,0\n", "more columns"},
      {head.substr(0, head.size() - 1) + ",distrusted_mask,column_sum_red\n100,1,2,0,0\n",
       "after distrusted_mask"},
      {head.substr(0, head.size() - 1) +
           ",distrusted_mask,column_sum_green,column_sum_red,side_px_red,side_px_green\n",
       "after distrusted_mask"},
      {with_columns + "100,1,2,0,0,639,0,0\n", "column_sum_green"},  // 2 pixels: 638 at most
      {with_columns + "100,1,2,0,320,0,0,0\n", "column_sum_red"},    // 1 pixel: 319 at most
      {with_columns + "100,1,2,0,0,638,2,0\n", "side_px_red"},       // 2 side pixels, 1 pixel
      {with_columns + "100,1,2,0,0,0,0,481\n", "side_px_green"},
      {with_columns + "100,1,2,0,-,-,-,0\n", "column_sum_red"},  // '-' is all or none
      {with_columns + "100,1,2,0,0,0,0\n", "side_px_green"},
      {with_columns + "100,1,2,0,0,0,0,0,0\n", "more columns"},
      {with_columns + "100,1,2,0,-,-,-,-,-\n", "more columns"},
      {with_columns.substr(0, with_columns.size() - 1) + ",row_sum_green,row_sum_red\n",
       "after distrusted_mask"},
      {with_rows + "100,1,2,0,0,0,0,0,240,0\n", "row_sum_red"},    // 1 pixel: row 239 at most
      {with_rows + "100,1,2,0,0,0,0,0,0,479\n", "row_sum_green"},  // 2 pixels: 478 at most
      {with_rows + "100,1,2,0,0,0,0,0,-,0\n", "row_sum_red"},      // '-' is all or none
      {with_rows + "100,1,2,0,-,-,-,-,0,0\n", "row sums given"},   // rows without columns
      {with_rows + "100,1,2,0,0,0,0,0,0\n", "row_sum_green"},
      {with_rows + "100,1,2,0,0,0,0,0,0,0,0\n", "more columns"},
  };
  for (const auto& [text, what] : cases) {
    ht::write_text(p, text);
    ht::expect_one_line(ht::error_of([&] { hd::read_area_log(p); }), p + ":", what);
  }
  ht::expect_one_line(ht::error_of([&] { hd::read_area_log(p + ".missing"); }), p, "cannot read");
}

// The whole training workflow without frames: record areas, train from them; the map must equal
// the one trained from the frames. A log measured with other thresholds is refused.
TEST(Trainer, FromAreaLogEqualsFromFrames) {
  ht::TempDir dir;
  const std::string run = dir.path("run");
  hs::simulate_dataset(hs::load_scenario("tiny"), 3, run, nullptr);
  const ha::ThresholdSet thresholds = ht::board_windows();
  const hs::AreaSeries from_frames = hs::segment_dataset(run, thresholds);
  {
    hd::AreaLogWriter w;
    ASSERT_TRUE(w.open(dir.path("areas.csv"), from_frames.image_width_px,
                       from_frames.image_height_px, thresholds, kNames));
    for (std::size_t i = 0; i < from_frames.areas.size(); ++i)
      w.write(from_frames.timestamp_ns[i], from_frames.areas[i]);
    ASSERT_TRUE(w.close());
  }
  hs::TrainOptions opt;
  opt.labels_path = run + "/labels.tum";
  opt.thresholds = thresholds;
  opt.dataset_dir = run;
  auto a = std::make_unique<ha::MapFile>();
  auto b = std::make_unique<ha::MapFile>();
  const hs::TrainReport ra = hs::train_map(opt, *a);
  opt.dataset_dir.clear();
  opt.areas_path = dir.path("areas.csv");
  // The area log brings no odometry: the run's encoder log goes beside it, decoded with the
  // robot's layout and geometry (the config's, which are the metadata's here).
  const hd::DatasetMetadata meta = hd::read_metadata(run);
  opt.encoders_path = run + "/encoders.log";
  opt.can_layout = meta.encoder_layout;
  opt.geometry = meta.geometry;
  // Nor the camera's offset, which the dataset's metadata gives (harmoloc-train
  // --camera-forward-m).
  opt.forward.camera_forward_m = meta.camera_forward_m;
  const hs::TrainReport rb = hs::train_map(opt, *b);
  EXPECT_TRUE(ra.placement.used);
  EXPECT_TRUE(rb.placement.used);
  EXPECT_EQ(ha::encode_map(*a), ha::encode_map(*b));
  EXPECT_EQ(ra.labelled, rb.labelled);
  EXPECT_GT(ra.labelled, 4U);
  EXPECT_GT(a->model.max_dissimilarity, 0.0F);
  EXPECT_LT(a->model.max_dissimilarity, 1.0F);

  hs::TrainOptions other = opt;
  other.thresholds.boards[1].saturation_min += 5;
  ht::expect_one_line(ht::error_of([&] { hs::train_map(other, *b); }), opt.areas_path,
                      "other colour thresholds");
  other = opt;
  other.thresholds = ht::board_windows(5);
  ht::expect_one_line(ht::error_of([&] { hs::train_map(other, *b); }), opt.areas_path,
                      "6 boards but the config has 5");
  other = opt;
  other.dataset_dir = run;  // both inputs at once
  ht::expect_one_line(ht::error_of([&] { hs::train_map(other, *b); }), "give either", "area log");
}
