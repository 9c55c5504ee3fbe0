#include "core/util/progress_bar.h"

#include <cstdio>
#include <string>

#include <gtest/gtest.h>

namespace lmd {
namespace {

std::string Lines(std::FILE* file) {
  std::rewind(file);
  std::string text;
  for (int c; (c = std::fgetc(file)) != EOF;) text.push_back(static_cast<char>(c));
  return text;
}

TEST(ProgressBarTest, OffATerminalPrintsOneLinePerTenthAndTheEnd) {
  std::FILE* file = std::tmpfile();
  {
    ProgressBar bar("maps", 100, file);
    for (int i = 1; i <= 100; ++i) bar.Update(i);
  }
  const std::string text = Lines(file);
  std::fclose(file);
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 11);  // 0 %, 10 %, ..., 100 %
  EXPECT_NE(text.find("maps [==============================] 100/100"), std::string::npos) << text;
}

TEST(ProgressBarTest, DoneMarksAnUnfinishedJob) {
  std::FILE* file = std::tmpfile();
  {
    ProgressBar bar("queries", 8, file);
    bar.Add(3);
    bar.Done();
  }
  const std::string text = Lines(file);
  std::fclose(file);
  EXPECT_NE(text.find("3/8"), std::string::npos) << text;
}

// lmdctl's choice: off a terminal its stderr carries only errors, so that a
// failed ingest is one line.
TEST(ProgressBarTest, OffATerminalItCanDrawNothing) {
  std::FILE* file = std::tmpfile();
  {
    ProgressBar bar("ingest", 10, file, ProgressBar::OffTerminal::kNothing);
    bar.Add(4);
    bar.Abandon();
    ProgressBar done("ingest", 10, file, ProgressBar::OffTerminal::kNothing);
    done.Update(10);
    done.Done();
  }
  const std::string text = Lines(file);
  std::fclose(file);
  EXPECT_EQ(text, "");
}

}  // namespace
}  // namespace lmd
