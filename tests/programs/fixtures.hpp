#pragma once
// Inputs shared by the program tests: the small pull scene of issue 17 and example sheets.
#include <nlohmann/json.hpp>
#include <string>

#include "process.hpp"

namespace papersim::test {

inline const std::string PAPERSIM = PAPERSIM_EXE;
inline const std::string SCENEGEN = SCENEGEN_EXE;

/// The scene.json of `papersim scenario pull --seed 1 --draw-only`, cut to `duration` 0.05 s
/// and `sheet.edge_length` 0.02 m (a run of about a second).
nlohmann::json small_scene(const Scratch& dir);

/// Write `scene` to DIR/NAME and return the path.
std::string write_scene(const Scratch& dir, const std::string& name, const nlohmann::json& scene);

/// `scenegen example KIND --out DIR/NAME`; returns the path.
std::string example_sheet(const Scratch& dir, const std::string& kind, const std::string& name);

}  // namespace papersim::test
