// SPDX-License-Identifier: Apache-2.0
// EXPECT_HAS(text, part): `text` (a std::string) contains `part`; the failure shows both.
#pragma once

#include <string>

#include <gtest/gtest.h>

#define EXPECT_HAS(text, part) EXPECT_NE((text).find(part), std::string::npos) << "want: " << (part) << "\n got: " << (text)
