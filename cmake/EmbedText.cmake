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

# shimmer_hash_files(OUT_CPP NAMESPACE FUNCTION FILES...)
# Generates a C++ source defining NAMESPACE::FUNCTION(), a hash of the
# files' texts, regenerated whenever one of them changes.
function(shimmer_hash_files out_cpp namespace function)
  set(files ${ARGN})
  add_custom_command(
    OUTPUT ${out_cpp}
    COMMAND ${CMAKE_COMMAND} -DOUT=${out_cpp} -DNAMESPACE=${namespace} -DFUNCTION=${function}
            "-DFILES=${files}" -P ${PROJECT_SOURCE_DIR}/cmake/HashFilesScript.cmake
    DEPENDS ${files} ${PROJECT_SOURCE_DIR}/cmake/HashFilesScript.cmake
    COMMENT "Hashing ${namespace}::${function}"
    VERBATIM)
endfunction()
