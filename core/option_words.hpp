// How the library names a run's options in its messages: neutrally, as
// {{name}} ("{{max_steps}}", "{{set}}"), so that each caller phrases them in
// its own words: the command line "--max-steps" and "--set"
// (experiments/cli.cpp), the Python module "max_steps" and "overrides"
// (python/pumasim_module.cpp). A name is the option's neutral spelling:
// lower-case letters, digits and '_'.
#pragma once

#include <cctype>
#include <functional>
#include <string>
#include <string_view>

namespace pumasim {

// "{{max_steps}}": an option as a library message names it.
inline std::string option_word(std::string_view name) { return "{{" + std::string(name) + "}}"; }

// A caller's word for an option, from its neutral name.
using OptionWords = std::function<std::string(std::string_view name)>;

// text with every {{name}} replaced by words(name), or by the name itself
// when words is empty. Anything else, braces included, is left as it is.
inline std::string phrased(std::string_view text, const OptionWords& words) {
  std::string out;
  out.reserve(text.size());
  std::size_t k = 0;
  while (k < text.size()) {
    const std::size_t open = text.find("{{", k);
    if (open == std::string_view::npos) break;
    std::size_t end = open + 2;
    while (end < text.size() && (std::islower(static_cast<unsigned char>(text[end])) ||
                                 std::isdigit(static_cast<unsigned char>(text[end])) || text[end] == '_')) {
      ++end;
    }
    const bool token = end > open + 2 && text.substr(end, 2) == "}}";
    out.append(text.substr(k, open - k));
    if (token) {
      const std::string_view name = text.substr(open + 2, end - open - 2);
      out += words ? words(name) : std::string(name);
      k = end + 2;
    } else {
      out += '{';  // the next '{' may open a token
      k = open + 1;
    }
  }
  out.append(text.substr(k));
  return out;
}

}  // namespace pumasim
