#pragma once
// Strict readers of the scenegen bench programs' option values: the whole text must be the
// value, else an error that names the option and the text (std::stoull read "-1" as 2^64 - 1).
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "scenegen/limits.hpp"

namespace papersim::scenegen::bench {

/// A whole number in [lo, hi], digits only.
inline unsigned long long whole_number(const std::string& option, const std::string& text,
                                       unsigned long long lo, unsigned long long hi) {
  char* end = nullptr;
  const bool digits = !text.empty() && text.size() <= 19 &&
                      text.find_first_not_of("0123456789") == std::string::npos;
  const unsigned long long v = digits ? std::strtoull(text.c_str(), &end, 10) : 0;
  if (!digits || v < lo || v > hi)
    throw std::runtime_error(option + " '" + text + "' is not a whole number from " +
                             std::to_string(lo) + " to " + std::to_string(hi));
  return v;
}

/// WIDTHxHEIGHT, each side from 8 to MAX_IMAGE_SIDE pixels.
inline void image_size(const std::string& option, const std::string& text, int& width,
                       int& height) {
  const auto x = text.find('x');
  if (x == std::string::npos)
    throw std::runtime_error(option + " '" + text + "' is not WIDTHxHEIGHT");
  const auto side = [&](const std::string& part) {
    return static_cast<int>(whole_number(option + " (in '" + text + "')", part, 8, MAX_IMAGE_SIDE));
  };
  width = side(text.substr(0, x));
  height = side(text.substr(x + 1));
}

}  // namespace papersim::scenegen::bench
