// papersim_metrics MESH... [--json] [--csv FILE] [--crease-angle DEG] [--plots DIR]
// The metrics command on its own (the papersim CLI wires the same function as a subcommand).
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "validation/metrics_command.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Measure sheet meshes: isometry, developability, creases, quality, "
               "self-intersection"};
  int exit_code = 0;
  papersim::validation::configure_metrics_command(app, exit_code, std::cout, std::cerr);
  try {
    CLI11_PARSE(app, argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "papersim_metrics: " << e.what() << '\n';
    return 1;
  }
  return exit_code;
}
