#pragma once
/// The exit statuses of papersim and scenegen (one table for both; README "Exit status").
namespace papersim::common {

enum ExitStatus : int {
  EXIT_OK = 0,
  EXIT_INTERNAL = 1,  ///< an unexpected error (a bug): please report it
  /// bad command line, scene, mesh, image or option value; a stated limit exceeded
  EXIT_BAD_INPUT = 2,
  EXIT_NO_CAMERA = 3,  ///< scenegen: no valid camera direction (meta.json records why)
  EXIT_NUMERIC = 4,   ///< papersim: numeric failure of the simulation (a step that cannot be taken)
  EXIT_OUTPUT = 5,    ///< an output cannot be written (full disk, file size limit, permission)
  EXIT_EXTERNAL = 6,  ///< a helper program failed (POV-Ray, gnuplot)
};

/// Status of a program stopped by signal `signal_number` (SIGINT: 130, SIGTERM: 143).
constexpr int exit_status_for_signal(int signal_number) { return 128 + signal_number; }

/// The table above as it appears in --help of both programs.
inline const char* exit_status_help() {
  return "Exit status: 0 success; 1 internal error (a bug); 2 bad input, usage or a stated limit "
         "exceeded; 3 no valid camera (scenegen); 4 numeric failure (papersim); 5 an output cannot "
         "be written (full disk, size limit, permission); 6 POV-Ray or gnuplot failed; 130 / 143 "
         "stopped by SIGINT / SIGTERM.";
}

}  // namespace papersim::common
