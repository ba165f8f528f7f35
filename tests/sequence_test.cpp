// Tests of sequence patterns, frame lists and the scan for frames on disk.
#include "io/sequence.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <climits>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <string>
#include <system_error>
#include <vector>

#include "io/temporary_files.h"
#include "ssgi/error.h"

namespace ssgi {
namespace {

namespace fs = std::filesystem;

using Frames = std::vector<int>;

// Runs `call`, expecting Error(kUsage) with a message that contains `needle`.
template <typename Call>
void ExpectUsageError(const Call& call, const std::string& needle) {
  SCOPED_TRACE(needle);
  try {
    call();
    ADD_FAILURE() << "no error thrown";
  } catch (const Error& error) {
    EXPECT_EQ(error.kind(), ErrorKind::kUsage);
    EXPECT_NE(std::string(error.what()).find(needle), std::string::npos) << error.what();
  }
}

TEST(SequencePatternTest, HashRunIsOneDigitPerHash) {
  const SequencePattern pattern = parse_sequence_pattern("room.####.exr");
  EXPECT_TRUE(pattern.has_frame_field);
  EXPECT_EQ(pattern.prefix, "room.");
  EXPECT_EQ(pattern.suffix, ".exr");
  EXPECT_EQ(pattern.padding, 4);
  EXPECT_EQ(pattern.path_for(1), "room.0001.exr");
  EXPECT_EQ(parse_sequence_pattern("a.##.exr").padding, 2);
  EXPECT_EQ(parse_sequence_pattern("a.#####.exr").padding, 5);
}

TEST(SequencePatternTest, LoneHashIsFourDigitsAsInOiiotool) {
  const SequencePattern pattern = parse_sequence_pattern("shot.#.exr");
  EXPECT_EQ(pattern.padding, 4);
  EXPECT_EQ(pattern.path_for(7), "shot.0007.exr");
}

TEST(SequencePatternTest, AtIsOneDigitEach) {
  EXPECT_EQ(parse_sequence_pattern("shot.@.exr").padding, 1);
  const SequencePattern pattern = parse_sequence_pattern("shot.@@@.exr");
  EXPECT_EQ(pattern.padding, 3);
  EXPECT_EQ(pattern.path_for(7), "shot.007.exr");
}

TEST(SequencePatternTest, LoneHashWithAtsAddsUpAsInOiiotool) {
  // The oiiotool manual's example: `#@@` is six digits.
  EXPECT_EQ(parse_sequence_pattern("shot.#@@.exr").padding, 6);
  EXPECT_EQ(parse_sequence_pattern("shot.##@.exr").padding, 3);
}

TEST(SequencePatternTest, PrintfFields) {
  const SequencePattern padded = parse_sequence_pattern("dir/shot_%04d.exr");
  EXPECT_EQ(padded.prefix, "dir/shot_");
  EXPECT_EQ(padded.suffix, ".exr");
  EXPECT_EQ(padded.padding, 4);
  EXPECT_EQ(padded.path_for(42), "dir/shot_0042.exr");

  const SequencePattern unpadded = parse_sequence_pattern("shot.%d.exr");
  EXPECT_TRUE(unpadded.has_frame_field);
  EXPECT_EQ(unpadded.padding, 0);
  EXPECT_EQ(unpadded.path_for(0), "shot.0.exr");
  EXPECT_EQ(unpadded.path_for(12), "shot.12.exr");
  EXPECT_EQ(parse_sequence_pattern("shot.%0007d.exr").padding, 7);
}

TEST(SequencePatternTest, FieldAtEitherEndOfTheName) {
  const SequencePattern leading = parse_sequence_pattern("out/####.exr");
  EXPECT_EQ(leading.prefix, "out/");
  EXPECT_EQ(leading.path_for(3), "out/0003.exr");
  const SequencePattern trailing = parse_sequence_pattern("frame_@@");
  EXPECT_EQ(trailing.suffix, "");
  EXPECT_EQ(trailing.path_for(3), "frame_03");
}

TEST(SequencePatternTest, NameWithoutFieldIsOneFile) {
  std::vector<int> frames = {99};
  const SequencePattern pattern = parse_sequence_pattern("renders/beauty.exr", &frames);
  EXPECT_FALSE(pattern.has_frame_field);
  EXPECT_EQ(pattern.prefix, "renders/beauty.exr");
  EXPECT_EQ(pattern.suffix, "");
  EXPECT_EQ(pattern.path_for(5), "renders/beauty.exr");
  EXPECT_EQ(frames, Frames{});  // cleared
}

TEST(SequencePatternTest, PercentNotStartingAFieldIsText) {
  const SequencePattern no_field = parse_sequence_pattern("mix_50%.exr");
  EXPECT_FALSE(no_field.has_frame_field);
  const SequencePattern field = parse_sequence_pattern("mix_50%x.%03d.exr");
  EXPECT_EQ(field.prefix, "mix_50%x.");
  EXPECT_EQ(field.padding, 3);
}

TEST(SequencePatternTest, FieldCharactersInDirectoriesAreText) {
  const SequencePattern pattern = parse_sequence_pattern("/mnt/take#2/user@host/%d/img.@@.exr");
  EXPECT_EQ(pattern.prefix, "/mnt/take#2/user@host/%d/img.");
  EXPECT_EQ(pattern.padding, 2);
  EXPECT_EQ(pattern.path_for(7), "/mnt/take#2/user@host/%d/img.07.exr");
  EXPECT_FALSE(parse_sequence_pattern("v###/plain.exr").has_frame_field);
}

TEST(SequencePatternTest, TwoFieldsAreAUsageError) {
  for (const std::string pattern : {"a.#.b.#.exr", "a.%04d.@.exr", "a.#%04d.exr", "#/a.#.@@"}) {
    ExpectUsageError([&] { parse_sequence_pattern(pattern); },
                     "\"" + pattern + "\" has 2 frame fields");
  }
}

TEST(SequencePatternTest, MalformedPatternsAreUsageErrors) {
  ExpectUsageError([] { parse_sequence_pattern(""); }, "empty sequence pattern");
  ExpectUsageError([] { parse_sequence_pattern("shot.%4d.exr"); }, "%4d pads with spaces");
  ExpectUsageError([] { parse_sequence_pattern("shot.%033d.exr"); }, "frame padding 33");
  ExpectUsageError([] { parse_sequence_pattern("shot.%099999999999999999999d.exr"); },
                   "frame padding");
  ExpectUsageError([] { parse_sequence_pattern("shot." + std::string(33, '#') + ".exr"); },
                   "frame padding 33");
}

TEST(SequencePatternTest, FrameListBeforeFieldIsTakenOut) {
  Frames frames;
  const SequencePattern pattern = parse_sequence_pattern("shot.1-5#.exr", &frames);
  EXPECT_EQ(pattern.prefix, "shot.");
  EXPECT_EQ(pattern.suffix, ".exr");
  EXPECT_EQ(pattern.padding, 4);
  EXPECT_EQ(pattern.path_for(3), "shot.0003.exr");
  EXPECT_EQ(frames, (Frames{1, 2, 3, 4, 5}));

  parse_sequence_pattern("shot.1,3,5-7%03d.exr", &frames);
  EXPECT_EQ(frames, (Frames{1, 3, 5, 6, 7}));
}

TEST(SequencePatternTest, FrameListWithStep) {
  Frames frames;
  const SequencePattern pattern = parse_sequence_pattern("shot.1-50x2####.exr", &frames);
  EXPECT_EQ(pattern.prefix, "shot.");
  EXPECT_EQ(pattern.padding, 4);
  ASSERT_EQ(frames.size(), 25u);
  EXPECT_EQ(frames.front(), 1);
  EXPECT_EQ(frames[1], 3);
  EXPECT_EQ(frames.back(), 49);
}

TEST(SequencePatternTest, NegativeFrameListAfterDotOrUnderscore) {
  Frames frames;
  EXPECT_EQ(parse_sequence_pattern("shot.-5--1#.exr", &frames).prefix, "shot.");
  EXPECT_EQ(frames, (Frames{-5, -4, -3, -2, -1}));
  EXPECT_EQ(parse_sequence_pattern("shot_-3-2%04d.exr", &frames).prefix, "shot_");
  EXPECT_EQ(frames, (Frames{-3, -2, -1, 0, 1, 2}));
  EXPECT_EQ(parse_sequence_pattern("dir/-2-1@@", &frames).prefix, "dir/");
  EXPECT_EQ(frames, (Frames{-2, -1, 0, 1}));
}

TEST(SequencePatternTest, HyphenInsideANameIsText) {
  Frames frames;
  EXPECT_EQ(parse_sequence_pattern("shot-1-5#.exr", &frames).prefix, "shot-");
  EXPECT_EQ(frames, (Frames{1, 2, 3, 4, 5}));
  EXPECT_EQ(parse_sequence_pattern("comp_v12-####.exr", &frames).prefix, "comp_v12-");
  EXPECT_EQ(frames, Frames{});
  EXPECT_EQ(parse_sequence_pattern("beauty-####.exr", &frames).prefix, "beauty-");
  EXPECT_EQ(frames, Frames{});
}

TEST(SequencePatternTest, DigitsRightBeforeFieldAreAFrameAsInOiiotool) {
  Frames frames;
  EXPECT_EQ(parse_sequence_pattern("take2#.exr", &frames).prefix, "take");
  EXPECT_EQ(frames, Frames{2});
  EXPECT_EQ(parse_sequence_pattern("box1-3#.exr", &frames).prefix, "box");
  EXPECT_EQ(frames, (Frames{1, 2, 3}));
}

TEST(SequencePatternTest, FramesInNameMayBeIgnored) {
  const SequencePattern pattern = parse_sequence_pattern("out.1-3#.exr", nullptr);
  EXPECT_EQ(pattern.prefix, "out.");
  EXPECT_EQ(pattern.path_for(2), "out.0002.exr");
}

TEST(SequencePatternTest, InvalidFrameListInNameIsAUsageError) {
  ExpectUsageError([] { parse_sequence_pattern("shot.1-5x0#.exr"); },
                   "frame list \"1-5x0\" in \"shot.1-5x0#.exr\": the step");
  ExpectUsageError([] { parse_sequence_pattern("shot.1-99999999999#.exr"); },
                   "frame list \"1-99999999999\" in \"shot.1-99999999999#.exr\": frame numbers");
  ExpectUsageError([] { parse_sequence_pattern("shot.3-9y1#.exr"); }, "selects no frames");
}

TEST(PathForTest, NegativeFramesPutTheSignBeforeThePadding) {
  const SequencePattern hashes = parse_sequence_pattern("shot.####.exr");
  EXPECT_EQ(hashes.path_for(-5), "shot.-0005.exr");
  EXPECT_EQ(hashes.path_for(-12345), "shot.-12345.exr");
  EXPECT_EQ(hashes.path_for(INT_MIN), "shot.-2147483648.exr");
  EXPECT_EQ(parse_sequence_pattern("shot.%d.exr").path_for(-3), "shot.-3.exr");
}

TEST(PathForTest, FramesWiderThanThePaddingKeepAllDigits) {
  const SequencePattern pattern = parse_sequence_pattern("shot.####.exr");
  EXPECT_EQ(pattern.path_for(0), "shot.0000.exr");
  EXPECT_EQ(pattern.path_for(12345), "shot.12345.exr");
  EXPECT_EQ(pattern.path_for(INT_MAX), "shot.2147483647.exr");
}

TEST(FrameListTest, SingleFrames) {
  EXPECT_EQ(parse_frame_list("7"), Frames{7});
  EXPECT_EQ(parse_frame_list("0"), Frames{0});
  EXPECT_EQ(parse_frame_list("-7"), Frames{-7});
  EXPECT_EQ(parse_frame_list("007"), Frames{7});
}

TEST(FrameListTest, Ranges) {
  EXPECT_EQ(parse_frame_list("1-5"), (Frames{1, 2, 3, 4, 5}));
  EXPECT_EQ(parse_frame_list("3-3"), Frames{3});
  EXPECT_EQ(parse_frame_list("5-1"), (Frames{5, 4, 3, 2, 1}));
}

TEST(FrameListTest, StepsCountFromTheFirstFrame) {
  EXPECT_EQ(parse_frame_list("1-10x3"), (Frames{1, 4, 7, 10}));
  EXPECT_EQ(parse_frame_list("1-10x4"), (Frames{1, 5, 9}));
  EXPECT_EQ(parse_frame_list("50-1x20"), (Frames{50, 30, 10}));
  EXPECT_EQ(parse_frame_list("1-3x10"), Frames{1});
}

TEST(FrameListTest, ComplementStepAsInOiiotool) {
  EXPECT_EQ(parse_frame_list("1-5y2"), (Frames{2, 4}));
  EXPECT_EQ(parse_frame_list("1-10y3"), (Frames{2, 3, 5, 6, 8, 9}));
  EXPECT_EQ(parse_frame_list("10-1y3"), (Frames{9, 8, 6, 5, 3, 2}));
}

TEST(FrameListTest, NegativeFrames) {
  EXPECT_EQ(parse_frame_list("-5--1"), (Frames{-5, -4, -3, -2, -1}));
  EXPECT_EQ(parse_frame_list("-3-2"), (Frames{-3, -2, -1, 0, 1, 2}));
  EXPECT_EQ(parse_frame_list("2--1"), (Frames{2, 1, 0, -1}));
  EXPECT_EQ(parse_frame_list("-1--7x3"), (Frames{-1, -4, -7}));
}

TEST(FrameListTest, CommaListsKeepOrderAndDropRepeats) {
  EXPECT_EQ(parse_frame_list("10,1-3,2,10,5"), (Frames{10, 1, 2, 3, 5}));
  EXPECT_EQ(parse_frame_list("1,3,5-7"), (Frames{1, 3, 5, 6, 7}));
  EXPECT_EQ(parse_frame_list("1-5y1,4"), Frames{4});  // an empty item is fine in a list
}

TEST(FrameListTest, ExtremeFramesDoNotOverflow) {
  EXPECT_EQ(parse_frame_list("2147483647"), Frames{INT_MAX});
  EXPECT_EQ(parse_frame_list("-2147483648"), Frames{INT_MIN});
  EXPECT_EQ(parse_frame_list("2147483646-2147483647"), (Frames{INT_MAX - 1, INT_MAX}));
  EXPECT_EQ(parse_frame_list("-2147483647--2147483648"), (Frames{INT_MIN + 1, INT_MIN}));
  EXPECT_EQ(parse_frame_list("-2147483648-2147483647x2147483647"),
            (Frames{INT_MIN, -1, INT_MAX - 1}));
}

TEST(FrameListTest, MalformedListsAreUsageErrorsNamingTheList) {
  for (const std::string spec : {"", "1-", "-", "x2", "a", "1a", "1,,2", "1,", ",1", "1-5x", "7x2",
                                 "1-5z2", " 1", "1 ", "1 - 5", "+3", "1.5", "1-2-3"}) {
    ExpectUsageError([&] { parse_frame_list(spec); }, "bad frame list \"" + spec + "\"");
  }
}

TEST(FrameListTest, InvalidStepsAreUsageErrors) {
  ExpectUsageError([] { parse_frame_list("1-5x0"); }, "frame list \"1-5x0\": the step");
  ExpectUsageError([] { parse_frame_list("1-5x-2"); }, "frame list \"1-5x-2\": the step");
  ExpectUsageError([] { parse_frame_list("1-5y0"); }, "frame list \"1-5y0\": the step");
}

TEST(FrameListTest, FramesOutsideIntAreUsageErrors) {
  for (const std::string spec :
       {"2147483648", "-2147483649", "1-2147483648", "99999999999999999999999999"}) {
    ExpectUsageError([&] { parse_frame_list(spec); },
                     "frame list \"" + spec + "\": frame numbers must lie in");
  }
}

TEST(FrameListTest, HugeAndEmptySelectionsAreUsageErrors) {
  ExpectUsageError([] { parse_frame_list("1-1000001"); },
                   "frame list \"1-1000001\": expands to more than 1000000 frames");
  ExpectUsageError([] { parse_frame_list("1-2000000000"); }, "more than 1000000 frames");
  ExpectUsageError([] { parse_frame_list("1-5y1"); }, "frame list \"1-5y1\" selects no frames");
  // A large step keeps a long range small.
  EXPECT_EQ(parse_frame_list("0-2000000000x1000000000"), (Frames{0, 1000000000, 2000000000}));
}

// Each test gets its own directory under the system's temporary directory, removed afterwards.
class FindFramesOnDiskTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string test_name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    dir_ = fs::temp_directory_path() /
           ("ssgi_sequence_test_" + test_name + "_" + std::to_string(std::random_device{}()));
    ASSERT_TRUE(fs::create_directories(dir_));
  }

  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }

  void Touch(const std::string& name) { std::ofstream(dir_ / name) << "x"; }

  std::string PatternIn(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

TEST_F(FindFramesOnDiskTest, FindsExactlyTheNamesPathForWrites) {
  const SequencePattern pattern = parse_sequence_pattern(PatternIn("shot.####.exr"));
  for (const int frame : {10, 1, 12345, -3, 2, -12345})
    Touch(fs::path(pattern.path_for(frame)).filename().string());
  for (const std::string other :
       {"shot.00012.exr",        // a leading zero path_for would not write for frame 12
        "shot.012.exr",          // too few digits
        "shot.-003.exr",         // printf's %04d for -3
        "shot.-0000.exr",        // frame 0 is 0000
        "shot.+0005.exr",        // no '+' sign
        "shot.0006.exr.tmp",     // other suffix
        "other.0007.exr",        // other prefix
        "shot.0008.EXR",         // names are case-sensitive
        "shot.abcd.exr",         // not a number
        "shot..exr",             // empty field
        "shot.99999999999.exr",  // beyond int
        "shot.0009exr"}) {
    Touch(other);
  }
  fs::create_directory(dir_ / "shot.0011.exr");  // a directory is not a frame
  EXPECT_EQ(find_frames_on_disk(pattern), (Frames{-12345, -3, 1, 2, 10, 12345}));
}

TEST_F(FindFramesOnDiskTest, UnpaddedField) {
  for (const std::string name : {"f.0.exr", "f.1.exr", "f.10.exr", "f.-2.exr", "f.01.exr"}) {
    Touch(name);
  }
  EXPECT_EQ(find_frames_on_disk(parse_sequence_pattern(PatternIn("f.%d.exr"))),
            (Frames{-2, 0, 1, 10}));
  // One `@` writes the same names as `%d`.
  EXPECT_EQ(find_frames_on_disk(parse_sequence_pattern(PatternIn("f.@.exr"))),
            (Frames{-2, 0, 1, 10}));
}

TEST_F(FindFramesOnDiskTest, FieldCharactersInTheDirectoryAreText) {
  ASSERT_TRUE(fs::create_directory(dir_ / "take#2@x"));
  Touch("take#2@x/img.07.exr");
  Touch("take#2@x/img.7.exr");
  EXPECT_EQ(find_frames_on_disk(parse_sequence_pattern(PatternIn("take#2@x/img.@@.exr"))),
            Frames{7});
}

TEST_F(FindFramesOnDiskTest, RangeInThePatternDoesNotLimitTheScan) {
  Touch("s.0001.exr");
  Touch("s.0009.exr");
  Frames frames;
  const SequencePattern pattern = parse_sequence_pattern(PatternIn("s.1-3#.exr"), &frames);
  EXPECT_EQ(frames, (Frames{1, 2, 3}));
  EXPECT_EQ(find_frames_on_disk(pattern), (Frames{1, 9}));
}

TEST_F(FindFramesOnDiskTest, RelativePatternSearchesTheWorkingDirectory) {
  Touch("rel.0004.exr");
  const fs::path saved = fs::current_path();
  fs::current_path(dir_);
  const Frames frames = find_frames_on_disk(parse_sequence_pattern("rel.####.exr"));
  fs::current_path(saved);
  EXPECT_EQ(frames, Frames{4});
}

TEST_F(FindFramesOnDiskTest, NothingToFind) {
  Touch("single.exr");
  EXPECT_EQ(find_frames_on_disk(parse_sequence_pattern(PatternIn("single.exr"))), Frames{});
  EXPECT_EQ(find_frames_on_disk(parse_sequence_pattern(PatternIn("none.####.exr"))), Frames{});
  EXPECT_EQ(find_frames_on_disk(parse_sequence_pattern(PatternIn("missing/shot.####.exr"))),
            Frames{});
  // A "directory" that is a file holds no frames either.
  EXPECT_EQ(find_frames_on_disk(parse_sequence_pattern(PatternIn("single.exr/shot.####.exr"))),
            Frames{});
}

TEST(FrameGapsTest, AGapIsARunOfMissingFramesOnTheShotsStep) {
  FrameGaps g = find_frame_gaps({1, 2, 4, 5, 6, 10, 11});
  EXPECT_EQ(g.step, 1);
  EXPECT_EQ(g.gaps, (std::vector<std::pair<int, int>>{{3, 3}, {7, 9}}));
  EXPECT_EQ(frame_gaps_text(g), "3, 7-9");
  // Rendered on twos: the odd frames are the shot, and only a missing odd frame is a gap.
  g = find_frame_gaps({1, 3, 5, 9, 11, 19});
  EXPECT_EQ(g.step, 2);
  EXPECT_EQ(g.gaps, (std::vector<std::pair<int, int>>{{7, 7}, {13, 17}}));
  EXPECT_EQ(frame_gaps_text(g), "7, 13-17x2");
  g = find_frame_gaps({-3, -1, 1, 3});
  EXPECT_EQ(g.step, 2);
  EXPECT_TRUE(g.gaps.empty());
  g = find_frame_gaps({-5, -4, -1});
  EXPECT_EQ(g.gaps, (std::vector<std::pair<int, int>>{{-3, -2}}));
  EXPECT_EQ(frame_gaps_text(g), "-3--2");
  // No gap without two frames; none either between the ends of int.
  EXPECT_TRUE(find_frame_gaps({}).gaps.empty());
  EXPECT_TRUE(find_frame_gaps({7}).gaps.empty());
  g = find_frame_gaps({INT_MIN, INT_MAX});
  EXPECT_EQ(g.step, int64_t{INT_MAX} - INT_MIN);
  EXPECT_TRUE(g.gaps.empty());
}

TEST(FrameGapsTest, ALongListNamesTheFirstGapsAndCountsTheRest) {
  Frames frames;
  for (int f = 1; f <= 40; f += 3) {  // 1, 2, 4, 5, ...: every third frame missing
    frames.push_back(f);
    frames.push_back(f + 1);
  }
  const FrameGaps g = find_frame_gaps(frames);
  EXPECT_EQ(g.gaps.size(), 13u);
  EXPECT_EQ(frame_gaps_text(g), "3, 6, 9, 12, 15, 18, 21, 24 and 5 more gaps");
}

}  // namespace
}  // namespace ssgi

// What a signal handler removes: the files registered while being written, and only those.
TEST(TemporaryFiles, RemovedWhileRegisteredAndKeptOtherwise) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("ssgi_temporary_files_test." + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  auto touch = [&](const std::string& name) {
    std::ofstream(dir / name) << "x";
    return (dir / name).string();
  };
  const std::string kept = touch("kept.exr");
  {
    std::vector<std::unique_ptr<ssgi::TemporaryFile>> writing;
    std::vector<std::string> paths;
    for (int k = 0; k < 3; ++k) {
      paths.push_back((dir / (".frame" + std::to_string(k) + ".tmp.exr")).string());
      writing.push_back(std::make_unique<ssgi::TemporaryFile>(paths.back()));
      touch(".frame" + std::to_string(k) + ".tmp.exr");
    }
    writing.erase(writing.begin());  // frame 0 finished: no longer a temporary file
    ssgi::remove_temporary_files();
    EXPECT_TRUE(std::filesystem::exists(paths[0]));
    EXPECT_FALSE(std::filesystem::exists(paths[1]));
    EXPECT_FALSE(std::filesystem::exists(paths[2]));
  }
  // Released slots are free again, and nothing registered is removed twice.
  const std::string later = touch(".later.tmp.exr");
  ssgi::remove_temporary_files();
  EXPECT_TRUE(std::filesystem::exists(later));
  EXPECT_TRUE(std::filesystem::exists(kept));
  std::filesystem::remove_all(dir);
}
