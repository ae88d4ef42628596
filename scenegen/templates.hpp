#pragma once
/// The POV-Ray templates of render_templates/, embedded in the library at build time so the
/// scenegen binary works from any directory.
#include <string>
#include <vector>

namespace papersim::scenegen {

/// Names of the embedded template files (main.pov, paper.inc, ...).
std::vector<std::string> template_names();
/// Text of a template: from `dir` when not empty, else the embedded copy.
/// @throw IoError when the template does not exist.
std::string template_text(const std::string& name, const std::string& dir = "");

}  // namespace papersim::scenegen
