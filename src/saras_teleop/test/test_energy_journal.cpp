#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>

#include <unistd.h>

#include "saras_teleop/energy_journal.h"

using saras_teleop::EnergyJournal;

namespace
{
std::string tempPath(const char* tag)
{
  return std::string(::testing::TempDir()) + "/energy_journal_" + tag + "_" + std::to_string(getpid());
}
}  // namespace

TEST(EnergyJournal, NewFileHasNoEnergyThenRestartReadsTheLastRecord)
{
  const std::string path = tempPath("restart");
  std::remove(path.c_str());
  const std::uint64_t token = EnergyJournal::newToken();
  {
    EnergyJournal j;
    EXPECT_TRUE(std::isnan(j.open(path, token)));
    j.record(10.0);
    j.record(7.25);  // the last completed step counts, not the largest
  }  // the process "dies": the mapping goes, the file keeps the value
  EnergyJournal again;
  EXPECT_DOUBLE_EQ(7.25, again.open(path, token));
  std::remove(path.c_str());
}

TEST(EnergyJournal, OpenedButNeverRecordedGivesNothing)
{
  const std::string path = tempPath("empty");
  std::remove(path.c_str());
  const std::uint64_t token = EnergyJournal::newToken();
  {
    EnergyJournal j;
    j.open(path, token);
  }
  EnergyJournal again;
  EXPECT_TRUE(std::isnan(again.open(path, token)));
  std::remove(path.c_str());
}

TEST(EnergyJournal, AnotherSessionStartsEmptyAndTakesTheFileOver)
{
  const std::string path = tempPath("session");
  std::remove(path.c_str());
  const std::uint64_t a = EnergyJournal::newToken();
  std::uint64_t b = EnergyJournal::newToken();
  while (b == a)
    b = EnergyJournal::newToken();
  {
    EnergyJournal j;
    j.open(path, a);
    j.record(9.0);
  }
  {
    EnergyJournal j;
    EXPECT_TRUE(std::isnan(j.open(path, b)));  // a previous platform run's energy is not ours
    j.record(2.0);
  }
  EnergyJournal back;
  EXPECT_TRUE(std::isnan(back.open(path, a)));  // and session a lost its claim
  std::remove(path.c_str());
}

TEST(EnergyJournal, CorruptFileGivesNothing)
{
  const std::string path = tempPath("corrupt");
  {
    std::ofstream f(path, std::ios::trunc);
    f << "not a journal, and of the wrong size";
  }
  EnergyJournal j;
  EXPECT_TRUE(std::isnan(j.open(path, 42)));
  j.record(3.0);
  EnergyJournal again;
  EXPECT_DOUBLE_EQ(3.0, again.open(path, 42));
  std::remove(path.c_str());
}

TEST(EnergyJournal, UnusablePathIsAClearError)
{
  EnergyJournal j;
  try
  {
    j.open("/nonexistent-dir/journal", 1);
    FAIL() << "expected an exception";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/journal"), std::string::npos);
  }
  EXPECT_FALSE(j.isOpen());
  j.record(1.0);  // no-op, no crash
}
