# Warnings as an INTERFACE target: every papersim target links papersim_warnings.
add_library(papersim_warnings INTERFACE)
add_library(papersim::warnings ALIAS papersim_warnings)
target_compile_options(papersim_warnings INTERFACE
  $<$<CXX_COMPILER_ID:GNU,Clang>:-Wall -Wextra -Wno-sign-compare>)

# Invariant checks (PAPERSIM_ASSERT) are on in Debug, and in Release when asked.
add_library(papersim_options INTERFACE)
add_library(papersim::options ALIAS papersim_options)
if(PAPERSIM_ASSERTS)
  target_compile_definitions(papersim_options INTERFACE PAPERSIM_ENABLE_ASSERTS=1)
endif()
target_compile_definitions(papersim_options INTERFACE $<$<CONFIG:Debug>:PAPERSIM_ENABLE_ASSERTS=1>)
