// Worker pools' tag names (common/job/worker_tags.h).
#include "common/job/worker_tags.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace portico {
namespace {

TEST(WorkerTags, NamesAreLettersDigitsDashUnderscoreAndDotStartingAlphanumeric) {
  for (const char* good : {"gpu", "bigmem", "Rack-7", "zone_b", "x86.avx512", "7th-floor"})
    EXPECT_EQ(tagNameProblem(good), "") << good;
  EXPECT_EQ(tagNameProblem(""), "a tag name is empty");
  EXPECT_EQ(tagNameProblem("-gpu"), "tag '-gpu' does not start with a letter or digit");
  EXPECT_EQ(tagNameProblem("big mem"), "tag 'big mem' holds a character other than letters, digits, '-', '_' and '.'");
  EXPECT_NE(tagNameProblem("a,b"), "");
  EXPECT_NE(tagNameProblem("caf\xc3\xa9"), "");
  EXPECT_EQ(tagNameProblem(std::string(kMaxTagLength, 'a')), "");
  EXPECT_NE(tagNameProblem(std::string(kMaxTagLength + 1, 'a')), "");
}

TEST(WorkerTags, NormalizedTagsAreSortedWithoutRepeatsAndBadOnesAreNamed) {
  EXPECT_EQ(normalizedTags({"red", "blue", "red"}, "--tag"), (std::vector<std::string>{"blue", "red"}));
  try {
    normalizedTags({"ok", "not ok"}, "--require");
    FAIL() << "a tag with a space was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "--require: tag 'not ok' holds a character other than letters, digits, '-', '_' and '.'");
  }
  std::vector<std::string> many;
  for (size_t i = 0; i <= kMaxTags; ++i) many.push_back("t" + std::to_string(i));
  EXPECT_THROW(normalizedTags(many, "--tag"), std::invalid_argument);
}

TEST(WorkerTags, AWorkerServesAJobOnlyWithEveryTagItRequires) {
  EXPECT_TRUE(hasAllTags({}, {}));
  EXPECT_TRUE(hasAllTags({"gpu"}, {}));
  EXPECT_FALSE(hasAllTags({}, {"gpu"}));
  EXPECT_TRUE(hasAllTags({"bigmem", "gpu", "ssd"}, {"bigmem", "ssd"}));
  EXPECT_FALSE(hasAllTags({"bigmem", "ssd"}, {"bigmem", "gpu"}));
}

TEST(WorkerTags, JoinedAndSplitAsJobsDbKeepsThem) {
  EXPECT_EQ(joinTags({"a", "b.c"}), "a b.c");
  EXPECT_EQ(splitTags("a b.c"), (std::vector<std::string>{"a", "b.c"}));
  EXPECT_TRUE(splitTags("").empty());
  EXPECT_TRUE(joinTags({}).empty());
}

}  // namespace
}  // namespace portico
