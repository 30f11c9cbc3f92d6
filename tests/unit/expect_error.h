#pragma once
// A check that a call throws mcr::Error of one kind with a message naming given words.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "util/error.h"

namespace mcr::testutil {

template <class Fn>
void expect_error(Errc code, const std::vector<std::string>& in_message, Fn&& fn) {
  try {
    fn();
    ADD_FAILURE() << "no mcr::Error thrown";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), code) << e.what();
    for (const std::string& s : in_message)
      EXPECT_NE(std::string(e.what()).find(s), std::string::npos) << "'" << s << "' not in: " << e.what();
  }
}

}  // namespace mcr::testutil
