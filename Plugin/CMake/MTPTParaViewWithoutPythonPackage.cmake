# find_package(ParaView) on Debian without python3-paraview installed
# (Documentation/environment.md).
#
# ParaView's CMake package (paraview-dev) always loads three export sets whose files belong to
# python3-paraview: VTK's Python modules (vtk/VTKPython-targets.cmake), ParaView's Python
# modules (ParaViewPython-targets.cmake) and the tools, pvpython among them
# (ParaViewTools-targets.cmake). Each generated file ends by checking that every file its
# targets name exists, and python3-paraview cannot be installed beside python3-vtk9, which
# Debian's VTK 9.1 (libvtk9-dev) needs. The plugin links none of these targets.
#
# A generated export file returns early, before that check, when all of its targets are
# already defined. So for each export set that names a missing file, this defines the set's
# targets first: executables as imported executables at their real location when that
# exists (pvserver, pvbatch), everything else as an empty interface target. Nothing is done
# when every file exists (python3-paraview installed), and no file of ParaView is changed.
#
# mtpt_define_missing_paraview_targets(<ParaView config dir>)
function (mtpt_define_missing_paraview_targets config_dir)
  set(export_files
    "${config_dir}/vtk/VTKPython-targets.cmake"
    "${config_dir}/ParaViewPython-targets.cmake"
    "${config_dir}/ParaViewPythonIncubator-targets.cmake"
    "${config_dir}/ParaViewTools-targets.cmake")
  foreach (export_file IN LISTS export_files)
    if (NOT EXISTS "${export_file}")
      continue ()
    endif ()
    file(STRINGS "${export_file}" expected
      REGEX "^foreach\\(_cmake_expected_target IN ITEMS ")
    string(REGEX REPLACE "^foreach\\(_cmake_expected_target IN ITEMS (.*)\\)$" "\\1"
      targets "${expected}")
    separate_arguments(targets)

    # The install prefix, as the generated file computes it: its folder, then one level up
    # per `get_filename_component(_IMPORT_PREFIX "${_IMPORT_PREFIX}" PATH)` line.
    get_filename_component(export_dir "${export_file}" DIRECTORY)
    file(STRINGS "${export_file}" levels
      REGEX "^get_filename_component\\(_IMPORT_PREFIX \"\\\${_IMPORT_PREFIX}\" PATH\\)")
    set(prefix "${export_dir}")
    foreach (level IN LISTS levels)
      get_filename_component(prefix "${prefix}" DIRECTORY)
    endforeach ()

    # The files that the per-configuration files check.
    get_filename_component(export_name "${export_file}" NAME_WE)
    file(GLOB config_files "${export_dir}/${export_name}-*.cmake")
    set(missing)
    set(locations)
    foreach (config_file IN LISTS config_files)
      file(STRINGS "${config_file}" checks REGEX "_cmake_import_check_files_for_")
      foreach (check IN LISTS checks)
        if (check MATCHES "_cmake_import_check_files_for_([^ ]+) \"([^\"]+)\"")
          set(target "${CMAKE_MATCH_1}")
          string(REPLACE "\${_IMPORT_PREFIX}" "${prefix}" file "${CMAKE_MATCH_2}")
          if (EXISTS "${file}")
            list(APPEND locations "${target}=${file}")
          else ()
            list(APPEND missing "${file}")
          endif ()
        endif ()
      endforeach ()
    endforeach ()
    if (NOT missing)
      continue ()
    endif ()

    list(LENGTH missing count)
    message(STATUS "MTPT: ${count} file(s) of ${export_name} missing (python3-paraview is "
      "not installed); defining its targets as placeholders so find_package(ParaView) works")
    foreach (target IN LISTS targets)
      if (TARGET "${target}")
        continue ()
      endif ()
      set(location)
      foreach (entry IN LISTS locations)
        if (entry MATCHES "^${target}=(.*)$")
          set(location "${CMAKE_MATCH_1}")
        endif ()
      endforeach ()
      if (export_name STREQUAL "ParaViewTools-targets" AND location)
        add_executable("${target}" IMPORTED)
        set_target_properties("${target}" PROPERTIES IMPORTED_LOCATION "${location}")
      else ()
        add_library("${target}" INTERFACE IMPORTED)
      endif ()
    endforeach ()
  endforeach ()
endfunction ()

# The client-server wrapping of the plugin's modules reads the wrapping hierarchy files of
# the modules they depend on, and Debian ships those files of ParaView's VTK and ParaView
# modules (lib/<arch>/vtk/hierarchy/ParaView) in python3-paraview as well. When they are
# missing, this points the modules' hierarchy property at the same files in `package_root`,
# the folder where python3-paraview's .deb is extracted (`dpkg-deb -x`; scripts/plugin.sh
# does it). Call after find_package(ParaView).
#
# mtpt_use_extracted_paraview_hierarchy(<package root or empty>)
function (mtpt_use_extracted_paraview_hierarchy package_root)
  get_property(targets DIRECTORY PROPERTY IMPORTED_TARGETS)
  set(hierarchy_dir "${package_root}/usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}/vtk/hierarchy/ParaView")
  set(redirected 0)
  foreach (target IN LISTS targets)
    get_target_property(type "${target}" TYPE)
    if (type STREQUAL "INTERFACE_LIBRARY")
      continue ()
    endif ()
    get_target_property(hierarchy "${target}" INTERFACE_vtk_module_hierarchy)
    if (NOT hierarchy OR EXISTS "${hierarchy}" OR NOT hierarchy MATCHES "/vtk/hierarchy/ParaView/")
      continue ()
    endif ()
    get_filename_component(name "${hierarchy}" NAME)
    set(extracted "${hierarchy_dir}/${name}")
    if (NOT package_root OR NOT EXISTS "${extracted}")
      message(FATAL_ERROR "MTPT: ${hierarchy} (module ${target}) is missing. Debian ships "
        "ParaView's wrapping hierarchy files in python3-paraview, which conflicts with "
        "python3-vtk9: extract its .deb without installing it (apt-get download "
        "python3-paraview; dpkg-deb -x python3-paraview_*.deb <dir>) and configure with "
        "-DMTPT_PARAVIEW_PACKAGE_ROOT=<dir>, as scripts/plugin.sh does.")
    endif ()
    set_property(TARGET "${target}" PROPERTY INTERFACE_vtk_module_hierarchy "${extracted}")
    math(EXPR redirected "${redirected} + 1")
  endforeach ()
  if (redirected)
    message(STATUS "MTPT: wrapping hierarchy of ${redirected} ParaView modules read from "
      "${package_root}")
  endif ()
endfunction ()
