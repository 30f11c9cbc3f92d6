#pragma once
// Checks that a call throws mcr::Error of one kind: with a message naming given words, or
// returning the message for the caller to look into.
#include <gtest/gtest.h>

#include <exception>
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

// Runs fn, expects mcr::Error with that code, returns the message ("" after a failure).
template <class Fn>
std::string expect_error(Errc code, Fn&& fn) {
  try {
    fn();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), code) << "got " << errc_name(e.code()) << ": " << e.what();
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected mcr::Error " << errc_name(code) << ", got std::exception: " << e.what();
    return "";
  }
  ADD_FAILURE() << "expected mcr::Error " << errc_name(code) << ", nothing thrown";
  return "";
}

inline bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

}  // namespace mcr::testutil
