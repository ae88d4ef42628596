#pragma once
/// PAPERSIM_ASSERT(cond, msg): an invariant check that throws std::logic_error naming the
/// condition, the message and the place. On in Debug builds and with PAPERSIM_ASSERTS=ON
/// (cmake/warnings.cmake); off, it compiles to nothing and `cond` is not evaluated.
#include <stdexcept>
#include <string>

#if defined(PAPERSIM_ENABLE_ASSERTS)
#define PAPERSIM_ASSERT(cond, msg)                                                               \
  do {                                                                                           \
    if (!(cond))                                                                                 \
      throw std::logic_error(std::string("papersim invariant failed: ") + #cond + " (" + (msg) + \
                             ") at " + __FILE__ + ":" + std::to_string(__LINE__));               \
  } while (0)
#else
#define PAPERSIM_ASSERT(cond, msg) \
  do {                             \
  } while (0)
#endif
