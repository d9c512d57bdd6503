# cmake -DSTEP=install|consumer -DBUILD_DIR=... -DWORK_DIR=... -DPREFIX=... -P run_package_test.cmake
# (arguments: tests/package/CMakeLists.txt). Fails with a message naming what is wrong.
cmake_minimum_required(VERSION 3.25)
set(stage ${WORK_DIR}/stage)
set(root ${stage}${PREFIX})

function(run)
  cmake_parse_arguments(R "" "WHAT" "COMMAND;ENV" ${ARGN})
  execute_process(COMMAND ${CMAKE_COMMAND} -E env ${R_ENV} ${R_COMMAND}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${R_WHAT}:\n${out}${err}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${R_WHAT} failed (${rc})")
  endif()
endfunction()

# ---- a staged install: DESTDIR + prefix -------------------------------------------
file(REMOVE_RECURSE ${stage})
run(WHAT "cmake --install (DESTDIR=${stage}, prefix ${PREFIX})"
    ENV DESTDIR=${stage}
    COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${PREFIX})

if(STEP STREQUAL "install")
  # Nothing outside the prefix (the Designer plugin and the QML module included).
  file(GLOB_RECURSE installed LIST_DIRECTORIES false RELATIVE ${stage} ${stage}/*)
  list(LENGTH installed n)
  set(outside "")
  foreach(f ${installed})
    if(NOT "/${f}" MATCHES "^${PREFIX}/")
      list(APPEND outside "/${f}")
    endif()
  endforeach()
  if(outside)
    message(FATAL_ERROR "installed outside the prefix ${PREFIX}: ${outside}")
  endif()
  message(STATUS "${n} files, all under ${PREFIX}")

  # The layout.
  foreach(f
      ${INCLUDEDIR}/drapekit/widget/drape_view.hpp
      ${INCLUDEDIR}/drapekit/widget/drape_widget_export.hpp
      ${INCLUDEDIR}/drapekit/widget/drape_enums.hpp
      ${INCLUDEDIR}/drapekit/engine/cloth/solver.hpp
      ${INCLUDEDIR}/drapekit/engine/library/u3m.hpp
      ${INCLUDEDIR}/drapekit/importers/body.hpp
      ${LIBDIR}/libdrape_widget.so ${LIBDIR}/libdrape_widget.so.0
      ${LIBDIR}/libdrape_cloth.a ${LIBDIR}/libdrape_core.a ${LIBDIR}/libdrape_fabric.a ${LIBDIR}/libdrape_record.a
      ${LIBDIR}/libdrape_capture.a ${LIBDIR}/libdrape_estimate.a ${LIBDIR}/libdrape_library.a ${LIBDIR}/libdrape_importers.a
      ${LIBDIR}/cmake/Drapekit/DrapekitConfig.cmake ${LIBDIR}/cmake/Drapekit/DrapekitConfigVersion.cmake
      ${LIBDIR}/cmake/Drapekit/DrapekitTargets.cmake ${LIBDIR}/cmake/Drapekit/FindCHOLMOD.cmake
      ${BINDIR}/drape
      ${DESIGNER_DIR}/libdrape_designer_plugin.so
      ${QML_DIR}/Drapekit/qmldir ${QML_DIR}/Drapekit/drape_widget.qmltypes ${QML_DIR}/Drapekit/libdrape_widgetplugin.so)
    if(NOT EXISTS ${root}/${f})
      message(FATAL_ERROR "missing from the install: ${PREFIX}/${f}")
    endif()
  endforeach()
  # The fit's internals (engine/estimate/detail: the evaluator, the stages, NLopt's
  # header) are not part of the package.
  foreach(f evaluator.hpp stages.hpp uncertainty.hpp)
    if(EXISTS ${root}/${INCLUDEDIR}/drapekit/engine/estimate/${f} OR EXISTS ${root}/${INCLUDEDIR}/drapekit/engine/estimate/detail/${f})
      message(FATAL_ERROR "an internal header of the fit is installed: engine/estimate/(detail/)${f}")
    endif()
  endforeach()
  if(NOT EXISTS ${root}/${INCLUDEDIR}/drapekit/engine/estimate/fit.hpp OR NOT EXISTS ${root}/${INCLUDEDIR}/drapekit/engine/estimate/predict.hpp)
    message(FATAL_ERROR "the fit's public headers (fit.hpp, predict.hpp) are missing from the install")
  endif()
  # Every exported target is there, namespaced.
  file(READ ${root}/${LIBDIR}/cmake/Drapekit/DrapekitTargets.cmake targets)
  foreach(t core cloth fabric record capture estimate library importers widget)
    if(NOT targets MATCHES "add_library\\(Drapekit::${t} ")
      message(FATAL_ERROR "DrapekitTargets.cmake does not define Drapekit::${t}")
    endif()
  endforeach()
  # Relocatable: no absolute path of the build, the source or the stage in the package files.
  file(GLOB cmake_files ${root}/${LIBDIR}/cmake/Drapekit/*.cmake)
  get_filename_component(src_dir ${CONSUMER_SOURCE}/../../.. ABSOLUTE)
  foreach(f ${cmake_files})
    file(READ ${f} text)
    foreach(bad ${BUILD_DIR} ${src_dir} ${stage})
      string(FIND "${text}" "${bad}" at)
      if(NOT at EQUAL -1)
        message(FATAL_ERROR "${f} names ${bad}: the package is not relocatable")
      endif()
    endforeach()
  endforeach()
  # The plugins find the installed library through $ORIGIN.
  find_program(READELF readelf REQUIRED)
  foreach(p ${DESIGNER_DIR}/libdrape_designer_plugin.so ${QML_DIR}/Drapekit/libdrape_widgetplugin.so)
    execute_process(COMMAND ${READELF} -d ${root}/${p} OUTPUT_VARIABLE dyn)
    if(NOT dyn MATCHES "R(UN)?PATH\\)[^\n]*\\[\\$ORIGIN/")
      message(FATAL_ERROR "${p}: no $ORIGIN-relative RUNPATH:\n${dyn}")
    endif()
    string(REGEX MATCH "\\[\\$ORIGIN/[^]]*\\]" rp "${dyn}")
    string(REGEX REPLACE "^\\[\\$ORIGIN/(.*)\\]$" "\\1" rel "${rp}")
    get_filename_component(pdir ${root}/${p} DIRECTORY)
    if(NOT EXISTS ${pdir}/${rel}/libdrape_widget.so.0)
      message(FATAL_ERROR "${p}: RUNPATH ${rp} does not lead to libdrape_widget.so.0")
    endif()
  endforeach()
  # The shared library shows its API, not the engine's or Eigen's internals.
  find_program(NM nm REQUIRED)
  execute_process(COMMAND ${NM} -DC --defined-only ${root}/${LIBDIR}/libdrape_widget.so OUTPUT_VARIABLE syms)
  string(REGEX MATCHALL "[^\n]+\n" lines "${syms}")
  set(foreign 0)
  foreach(l ${lines})
    if(l MATCHES " [TDB] " AND NOT l MATCHES "drape::widget::|qml_register_types_Drapekit| (__bss_start|_edata|_end|_init|_fini)\n")
      math(EXPR foreign "${foreign} + 1")
      message(STATUS "exported and not ours: ${l}")
    endif()
  endforeach()
  if(foreign GREATER 0)
    message(FATAL_ERROR "libdrape_widget.so exports ${foreign} functions or data outside drape::widget")
  endif()
  return()
endif()

# ---- an independent project against the staged package ------------------------------
set(build ${WORK_DIR}/consumer-build)
file(REMOVE_RECURSE ${build})
run(WHAT "configure the consumer project"
    COMMAND ${CMAKE_COMMAND} -S ${CONSUMER_SOURCE} -B ${build} -G ${GENERATOR} -DCMAKE_BUILD_TYPE=Release
            -DCMAKE_PREFIX_PATH=${root})
run(WHAT "build the consumer project" COMMAND ${CMAKE_COMMAND} --build ${build})

set(tmp ${WORK_DIR}/consumer-run)
file(REMOVE_RECURSE ${tmp})
file(MAKE_DIRECTORY ${tmp})
# No path into the build tree: the installed libraries and plugins only.
set(clean_env --unset=LD_LIBRARY_PATH --unset=QT_PLUGIN_PATH --unset=QML_IMPORT_PATH --unset=QML2_IMPORT_PATH
    HOME=${tmp} XDG_DATA_HOME=${tmp}/data --unset=DRAPE_LIBRARY)
run(WHAT "DrapeView drapes a library fabric by name"
    ENV ${clean_env}
    COMMAND ${GUI_RUNNER} ${build}/drape_consumer ${tmp}/library.sqlite ${tmp}/consumer.png)
run(WHAT "the installed Designer plugin loads"
    ENV ${clean_env}
    COMMAND ${GUI_RUNNER} ${build}/plugin_check ${root}/${DESIGNER_DIR}/libdrape_designer_plugin.so ${root})
run(WHAT "a QML-only host imports Drapekit"
    ENV ${clean_env} QML_IMPORT_PATH=${root}/${QML_DIR}
    COMMAND ${GUI_RUNNER} ${build}/qml_host ${CONSUMER_SOURCE}/host.qml ${root})
