# Private warning flags for normalflow's own targets (never leaked to consumers).
add_library(normalflow_warnings INTERFACE)
target_compile_options(normalflow_warnings INTERFACE -Wall -Wextra -Wpedantic
  $<$<BOOL:${NORMALFLOW_WERROR}>:-Werror>)
if(NORMALFLOW_SANITIZE)
  target_compile_options(normalflow_warnings INTERFACE -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  target_link_options(normalflow_warnings INTERFACE -fsanitize=address,undefined)
endif()
install(TARGETS normalflow_warnings EXPORT normalflowTargets)
