# shimmer_embed_text(OUT_CPP NAMESPACE SYMBOL_PREFIX FILES...)
# Generates a C++ source that holds each file's text as a string_view, so
# binaries carry the GLSL shading core and never look for it on disk.
# Regenerated whenever one of the files changes.
function(shimmer_embed_text out_cpp namespace)
  set(files ${ARGN})
  add_custom_command(
    OUTPUT ${out_cpp}
    COMMAND ${CMAKE_COMMAND} -DOUT=${out_cpp} -DNAMESPACE=${namespace}
            "-DFILES=${files}" -P ${PROJECT_SOURCE_DIR}/cmake/EmbedTextScript.cmake
    DEPENDS ${files} ${PROJECT_SOURCE_DIR}/cmake/EmbedTextScript.cmake
    COMMENT "Embedding ${namespace} sources"
    VERBATIM)
endfunction()
