# Install and export rules shared by every library folder.
#
# drape_library_target(target export_name) - call in the folder that defines
# `target`, after add_library:
#   * the include directories: the source tree while building, and after
#     installing <prefix>/include/drapekit (so "engine/cloth/solver.hpp" and
#     "widget/drape_view.hpp" resolve as they do in the tree) plus
#     <prefix>/include (so <drapekit/widget/drape_view.hpp> does too);
#   * the namespaced name Drapekit::<export_name> (an alias in the tree, so a
#     project using add_subdirectory/FetchContent links the same names as one
#     using find_package), and drape::<export_name> as before;
#   * installs the library into the DrapekitTargets export set and the
#     folder's headers to <prefix>/include/drapekit/<folder>/.
include(GNUInstallDirs)

function(drape_library_target target export_name)
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${export_name})
  if(NOT TARGET Drapekit::${export_name})
    add_library(Drapekit::${export_name} ALIAS ${target})
  endif()
  if(NOT TARGET drape::${export_name})
    add_library(drape::${export_name} ALIAS ${target})
  endif()
  target_include_directories(${target} PUBLIC
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/drapekit>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  install(TARGETS ${target} EXPORT DrapekitTargets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT devel
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT runtime NAMELINK_COMPONENT devel
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)
  file(RELATIVE_PATH _rel ${PROJECT_SOURCE_DIR} ${CMAKE_CURRENT_SOURCE_DIR})
  file(GLOB _headers CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.hpp)
  install(FILES ${_headers} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/drapekit/${_rel} COMPONENT devel)
  set_property(GLOBAL APPEND PROPERTY DRAPEKIT_EXPORTED_TARGETS ${export_name})
endfunction()

# drape_relative_rpath(out from_dir to_dir): "$ORIGIN/<path from from_dir to
# to_dir>", both relative to the install prefix, for an installed module (a
# plugin) that finds the installed libraries wherever the prefix is moved to.
function(drape_relative_rpath out from_dir to_dir)
  file(RELATIVE_PATH _rel "/__prefix__/${from_dir}" "/__prefix__/${to_dir}")
  if(_rel STREQUAL "")
    set(${out} "$ORIGIN" PARENT_SCOPE)
  else()
    set(${out} "$ORIGIN/${_rel}" PARENT_SCOPE)
  endif()
endfunction()
