#include "common/photometry/ies_file.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "tests/unit/photometry/ies_test_files.h"

namespace portico {
namespace {

using ies_test::angles;
using ies_test::iesText;

const std::string kFlat = iesText(angles(0, 90, 45), {0}, [](double, double) { return 100.0; });

// The one-line message parseIes throws for `text`.
std::string errorOf(const std::string& text) {
  try {
    parseIes(text, "lamp.ies");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(IesFile, ReadsTheHeaderFieldsAndScalesTheCandelaValues) {
  const IesPhotometry ies = parseIes(iesText(angles(0, 90, 45), {0, 90}, [](double v, double h) { return v + h; },
                                             2.0, 0.9),
                                     "lamp.ies");
  EXPECT_EQ(ies.standard, "LM-63-2002");
  EXPECT_EQ(ies.lampCount, 1);
  EXPECT_EQ(ies.lumensPerLamp, -1);
  EXPECT_EQ(ies.ratedLumens(), -1);
  EXPECT_DOUBLE_EQ(ies.candelaMultiplier, 2.0);
  EXPECT_DOUBLE_EQ(ies.ballastFactor, 0.9);
  EXPECT_DOUBLE_EQ(ies.width, 0.1);
  EXPECT_EQ(ies.grid.vertical, (std::vector<double>{0, 45, 90}));
  EXPECT_EQ(ies.grid.horizontal, (std::vector<double>{0, 90}));
  ASSERT_EQ(ies.grid.candela.size(), 6u);
  // Horizontal-major, times multiplier x ballast factor = 1.8.
  EXPECT_DOUBLE_EQ(ies.grid.candela[1], 45 * 1.8);
  EXPECT_DOUBLE_EQ(ies.grid.candela[5], 180 * 1.8);
}

TEST(IesFile, TheBallastLampFactorScalesOnlyFilesBeforeLm63_2002) {
  const auto peak = [](const std::string& header, double third) {
    return parseIes(iesText(angles(0, 90, 90), {0}, [](double, double) { return 100.0; }, 1, 1, header, third), "x.ies")
        .grid.candela[0];
  };
  EXPECT_DOUBLE_EQ(peak("IESNA:LM-63-1995", 0.95), 95.0);
  EXPECT_DOUBLE_EQ(peak("IESNA91", 0.5), 50.0);
  // LM-63-2002: "future use"; LM-63-2019: the file generation type (1.00001 and the like).
  EXPECT_DOUBLE_EQ(peak("IESNA:LM-63-2002", 1.0), 100.0);
  EXPECT_DOUBLE_EQ(peak("IES:LM-63-2019", 1.00001), 100.0);
  EXPECT_EQ(parseIes(iesText(angles(0, 90, 90), {0}, [](double, double) { return 1.0; }, 1, 1, "IES:LM-63-2019"), "x")
                .standard,
            "LM-63-2019");
}

TEST(IesFile, ReadsNumbersSplitByCommasAndLineEndsAnywhere) {
  const std::string text =
      "IESNA:LM-63-1995\r\n[TEST] commas\r\nTILT=NONE\r\n2 1500,1.0 3\r\n1 1 1 0 0 0 1 1\r\n10\r\n0,45\r\n90\r\n0\r\n"
      "300 200\r\n100\r\n";
  const IesPhotometry ies = parseIes(text, "commas.ies");
  EXPECT_EQ(ies.lampCount, 2);
  EXPECT_EQ(ies.ratedLumens(), 3000);
  EXPECT_EQ(ies.grid.candela, (std::vector<double>{300, 200, 100}));
}

TEST(IesFile, ReadsAFileWithoutAHeaderLine) {
  const std::string text = "Some luminaire\nTILT=NONE\n1 -1 1 2 1 1 2 0 0 0\n1 1 0\n0 90\n0\n10 5\n";
  const IesPhotometry ies = parseIes(text, "old.ies");
  EXPECT_EQ(ies.standard, "LM-63-1986");
  EXPECT_EQ(ies.grid.candela, (std::vector<double>{10, 5}));
}

TEST(IesFile, ReadsAFileOnDiskAndNamesAMissingOne) {
  const std::filesystem::path path = std::filesystem::temp_directory_path() / "portico-ies-test.ies";
  std::ofstream(path) << kFlat;
  EXPECT_EQ(readIesFile(path.string()).grid.candela.size(), 3u);
  std::filesystem::remove(path);
  try {
    readIesFile(path.string());
    FAIL() << "a missing file was read";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), path.string() + ": cannot be read");
  }
}

// kFlat with the first (or, with `last`, the last) `from` replaced by `to`.
std::string flatWith(const std::string& from, const std::string& to, bool last = false) {
  std::string text = kFlat;
  text.replace(last ? text.rfind(from) : text.find(from), from.size(), to);
  return text;
}

// Every refusal is one line naming the file, the line and the problem.
TEST(IesFile, BadFilesGiveOneLineErrorsNamingTheLine) {
  EXPECT_EQ(errorOf(""), "lamp.ies: line 1: no TILT= line: not an IES LM-63 photometric file");
  EXPECT_EQ(errorOf(flatWith("TILT=NONE", "TILT=INCLUDE")),
            "lamp.ies: line 4: TILT=INCLUDE (lamp output by tilt angle) is not supported; only TILT=NONE");
  EXPECT_EQ(errorOf(flatWith("TILT=NONE", "TILT=lamp.tlt")),
            "lamp.ies: line 4: TILT=lamp.tlt (a tilt file) is not supported; only TILT=NONE");
  // Truncated: the last candela value is missing.
  EXPECT_EQ(errorOf(kFlat.substr(0, kFlat.rfind("100"))),
            "lamp.ies: line 9: the file ends before candela value 3 of 3 (horizontal angle 0, vertical angle 90) "
            "(truncated?)");
  EXPECT_EQ(errorOf(flatWith("100", "-100", true)),
            "lamp.ies: line 9: candela value -100 (horizontal angle 0, vertical angle 90) is negative");
  EXPECT_EQ(errorOf(flatWith("100", "1OO", true)),
            "lamp.ies: line 9: '1OO' is not a number (candela value 3 of 3 (horizontal angle 0, vertical angle 90))");
  EXPECT_EQ(errorOf(kFlat + "7\n"),
            "lamp.ies: line 10: '7' follows the last candela value (more values than the angle counts say)");
  EXPECT_EQ(errorOf(flatWith("1 -1 1 3 1 1 2", "1 -1 1 3 1 2 2")),
            "lamp.ies: line 5: photometric type 2 (B) is not supported; only type C (1)");
  EXPECT_EQ(errorOf(flatWith("0 45 90", "0 45 45")),
            "lamp.ies: line 7: vertical angle 3 (45) does not increase from the one before (45)");
  EXPECT_EQ(errorOf(flatWith("0 45 90", "0 45 80")),
            "lamp.ies: line 7: the vertical angles run 0-80; type C runs from 0 or 90 to 90 or 180 degrees");
  EXPECT_EQ(errorOf(iesText(angles(0, 90, 45), {0, 45}, [](double, double) { return 1.0; })),
            "lamp.ies: line 8: the horizontal angles run 0-45; type C runs 0, 0-90, 0-180, 90-270 or 0-360 degrees");
  EXPECT_EQ(errorOf(flatWith("1 -1 1 3 1", "1 -1 0 3 1")), "lamp.ies: line 5: the candela multiplier = 0 must be above 0");
  EXPECT_EQ(errorOf(flatWith("1 -1 1 3 1", "1 -1 1 3.5 1")),
            "lamp.ies: line 5: the number of vertical angles = 3.5 must be a whole number from 2 to 100000");
}

}  // namespace
}  // namespace portico
