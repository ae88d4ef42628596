#pragma once
/// Whether text from outside (a file or folder name, a command-line value) can go into JSON: the
/// JSON files we write are UTF-8, and nlohmann::json refuses to dump a string that is not.
#include <string_view>

namespace papersim::common {

/// Whether `text` is well-formed UTF-8 (RFC 3629): no stray continuation byte, no sequence cut
/// short, no overlong form, no surrogate (U+D800-U+DFFF), nothing above U+10FFFF. The same
/// strings nlohmann::json dumps without an error.
bool is_utf8(std::string_view text);

}  // namespace papersim::common
