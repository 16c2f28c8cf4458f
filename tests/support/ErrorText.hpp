#pragma once
// Checking the typed errors the library throws by their message.

#include <gtest/gtest.h>

#include <functional>
#include <string>

namespace rovermap::testing {

/// The message of the `Error` that `f` throws; a test failure (and "") if it throws nothing.
template <typename Error>
std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an exception";
  return "";
}

/// Passes if `text` contains `part`; a failure shows both.
inline ::testing::AssertionResult Contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << "\"" << text << "\"\n does not contain \"" << part << "\"";
}

}  // namespace rovermap::testing
