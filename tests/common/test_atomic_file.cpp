// SPDX-License-Identifier: Apache-2.0
// files::read_all's size limit (checked before any read) and its refusal of what is
// not a regular file, without blocking on a FIFO.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <string>

#include "elaslam/common/atomic_file.hpp"

namespace elaslam {
namespace {

std::string temp_path(const std::string& name) {
  return ::testing::TempDir() + "/atomic_file_" + std::to_string(::getpid()) + "_" + name;
}

TEST(AtomicSave, ReadAllRefusesAFileBeyondItsLimitBeforeReadingIt) {
  const std::string path = temp_path("limit");
  std::string why;
  ASSERT_TRUE(files::write_atomic(path, "0123456789", &why)) << why;
  std::string out = "untouched";
  bool missing = true;
  EXPECT_FALSE(files::read_all(path, &out, &why, &missing, 9));
  EXPECT_FALSE(missing);
  EXPECT_NE(why.find("is 10 bytes, more than the 9 accepted"), std::string::npos) << why;
  EXPECT_EQ(out, "untouched");  // not read at all
  ASSERT_TRUE(files::read_all(path, &out, &why, &missing, 10)) << why;
  EXPECT_EQ(out, "0123456789");
  ASSERT_TRUE(files::read_all(path, &out, &why)) << why;  // no limit
  EXPECT_EQ(out, "0123456789");
  std::remove(path.c_str());
  EXPECT_FALSE(files::read_all(path, &out, &why, &missing, 10));
  EXPECT_TRUE(missing);
}

TEST(AtomicSave, ReadAllRefusesAFifoWithoutWaitingForAWriter) {
  const std::string path = temp_path("fifo");
  std::remove(path.c_str());
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  std::string out, why;
  EXPECT_FALSE(files::read_all(path, &out, &why));  // before: open(2) waited for a writer forever
  EXPECT_NE(why.find("is not a regular file"), std::string::npos) << why;
  std::remove(path.c_str());
}

}  // namespace
}  // namespace elaslam
