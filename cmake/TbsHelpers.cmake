# Shared settings for every tbs target: C++20, warnings on, no global flags.
function(tbs_target_defaults target)
  target_compile_features(${target} PUBLIC cxx_std_20)
  set_target_properties(${target} PROPERTIES CXX_EXTENSIONS OFF)
  if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic)
  endif()
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
    # GCC 12 reports false -Wrestrict/-Warray-bounds positives inside libstdc++ (GCC bug 105329).
    target_compile_options(${target} PRIVATE -Wno-restrict -Wno-array-bounds)
  endif()
endfunction()

# tbs_add_library(<name> SOURCES ...): a component library with public headers under
# <dir>/include and the alias tbs::<name>.
function(tbs_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES" ${ARGN})
  add_library(tbs_${name} ${ARG_SOURCES})
  add_library(tbs::${name} ALIAS tbs_${name})
  target_include_directories(tbs_${name} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:include>)
  set_target_properties(tbs_${name} PROPERTIES EXPORT_NAME ${name} POSITION_INDEPENDENT_CODE ON)
  tbs_target_defaults(tbs_${name})
endfunction()

# tbs_add_cgal_sources(<target> SOURCES ... LIBRARIES ...): compiles the sources of a tbs
# library that include CGAL as an object library of their own and adds them to <target>.
# CGAL's exact predicates need -frounding-math, which CGAL::CGAL adds to every file it is
# linked to; this way only the files that call CGAL get it, and the evaluator's hot loops do
# not. LIBRARIES: what those sources need besides CGAL (their usage requirements only).
function(tbs_add_cgal_sources target)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBRARIES" ${ARGN})
  add_library(${target}_cgal OBJECT ${ARG_SOURCES})
  target_include_directories(${target}_cgal PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/include ${TBS_INTERNAL_DIR})
  target_link_libraries(${target}_cgal PRIVATE CGAL::CGAL ${ARG_LIBRARIES})
  set_target_properties(${target}_cgal PROPERTIES POSITION_INDEPENDENT_CODE ON)
  tbs_target_defaults(${target}_cgal)
  target_sources(${target} PRIVATE $<TARGET_OBJECTS:${target}_cgal>)
endfunction()
