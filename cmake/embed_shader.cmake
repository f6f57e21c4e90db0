# Embeds a shader file as a C++ raw string literal: generates a header declaring
#   namespace lightvol::detail { inline constexpr char VARIABLE[] = R"lightvol_glsl(...)lightvol_glsl"; }
# lightvol_embed_shader(SOURCE OUTPUT VARIABLE) runs at configure time and again whenever SOURCE
# changes (it is a configure dependency).
function(lightvol_embed_shader source output variable)
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS "${source}")
  file(READ "${source}" text)
  string(FIND "${text}" ")lightvol_glsl\"" clash)
  if(NOT clash EQUAL -1)
    message(FATAL_ERROR "${source} contains the raw string delimiter )lightvol_glsl\"")
  endif()
  file(RELATIVE_PATH name "${PROJECT_SOURCE_DIR}" "${source}")
  set(content "// Generated from ${name} by cmake/embed_shader.cmake: edit the shader, not this file.\n#pragma once\n\nnamespace lightvol::detail {\ninline constexpr char ${variable}[] = R\"lightvol_glsl(${text})lightvol_glsl\";\n}  // namespace lightvol::detail\n")
  # Rewritten only when it changes, so that an unrelated reconfigure rebuilds nothing.
  if(EXISTS "${output}")
    file(READ "${output}" old)
    if(old STREQUAL content)
      return()
    endif()
  endif()
  file(WRITE "${output}" "${content}")
endfunction()
