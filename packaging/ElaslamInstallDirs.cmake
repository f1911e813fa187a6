# SPDX-License-Identifier: Apache-2.0
# The installed paths of elaslam for an install prefix, as GNUInstallDirs derives
# them, and the install steps whose output depends on them (systemd units, the
# files in /etc). Used twice:
# - when installing (`cmake --install --prefix P`, cpack's staging install with
#   prefix /usr), from install(CODE) in packaging/CMakeLists.txt: the prefix is
#   only known then, so that units name P/bin/... and a /usr package gets /etc;
# - when configuring, for the package's conffiles list.
# Inputs (variables set by the caller): ELASLAM_REL_BINDIR, ELASLAM_REL_SYSCONFDIR,
# ELASLAM_REL_DOCDIR (GNUInstallDirs' relative CMAKE_INSTALL_<dir>).

# elaslam_install_dirs(<prefix>): sets in the caller's scope
#   ELASLAM_BINDIR   <prefix>/bin
#   ELASLAM_DATADIR  <prefix>/share/elaslam (fixed: the programs find their data
#                    there, relative to their own directory; common/cli.hpp)
#   ELASLAM_DOCDIR   <prefix>/share/doc/elaslam
#   ELASLAM_UNITDIR  <prefix>/lib/systemd/system (not LIBDIR: Debian's is multiarch)
#   ELASLAM_ETCDIR   /etc/elaslam for the prefixes / and /usr (packages),
#                    /etc/opt/X/elaslam for /opt/X, else <prefix>/etc/elaslam
#                    (GNUInstallDirs' rule for CMAKE_INSTALL_FULL_SYSCONFDIR)
function(elaslam_install_dirs prefix)
  string(REGEX REPLACE "(.)/+$" "\\1" prefix "${prefix}")
  foreach(d BINDIR DOCDIR)
    if(IS_ABSOLUTE "${ELASLAM_REL_${d}}")
      set(ELASLAM_${d} "${ELASLAM_REL_${d}}" PARENT_SCOPE)
    else()
      set(ELASLAM_${d} "${prefix}/${ELASLAM_REL_${d}}" PARENT_SCOPE)
    endif()
  endforeach()
  set(ELASLAM_DATADIR "${prefix}/share/elaslam" PARENT_SCOPE)
  set(ELASLAM_UNITDIR "${prefix}/lib/systemd/system" PARENT_SCOPE)
  set(etc "${ELASLAM_REL_SYSCONFDIR}")
  if(IS_ABSOLUTE "${etc}")
    # as given
  elseif(prefix STREQUAL "/" OR prefix STREQUAL "/usr")
    set(etc "/${etc}")
  elseif(prefix MATCHES "^/opt/")
    set(etc "/${etc}${prefix}")
  else()
    set(etc "${prefix}/${etc}")
  endif()
  string(REPLACE "//" "/" etc "${etc}")
  set(ELASLAM_ETCDIR "${etc}/elaslam" PARENT_SCOPE)
endfunction()

# Programs look at /etc/elaslam/elaslam.yaml whatever their prefix (common/cli.hpp).
# For a prefix whose /etc files land elsewhere, the units point them at those.
function(_elaslam_config_place)
  if(ELASLAM_ETCDIR STREQUAL "/etc/elaslam")
    set(ELASLAM_CONFIG_PLACE "/etc/elaslam/elaslam.yaml (the program finds it itself)" PARENT_SCOPE)
    set(ELASLAM_CONFIG_ENVIRONMENT "" PARENT_SCOPE)
  else()
    set(ELASLAM_CONFIG_PLACE "${ELASLAM_ETCDIR}/elaslam.yaml (ELASLAM_CONFIG below)" PARENT_SCOPE)
    set(ELASLAM_CONFIG_ENVIRONMENT "Environment=ELASLAM_CONFIG=${ELASLAM_ETCDIR}/elaslam.yaml\n" PARENT_SCOPE)
  endif()
endfunction()

# A scratch folder (under the build tree) for files made at install time, one per
# install destination so that concurrent installs do not mix; removed afterwards.
function(_elaslam_work_dir out base)
  string(MD5 h "$ENV{DESTDIR}|${CMAKE_INSTALL_PREFIX}")
  string(RANDOM LENGTH 8 r)
  set(${out} "${base}/${h}-${r}" PARENT_SCOPE)
endfunction()

# elaslam_install_units(<work dir> <hardening.inc> <unit.in>...): configures the
# units for CMAKE_INSTALL_PREFIX and installs them into ELASLAM_UNITDIR (under
# $DESTDIR; file(INSTALL) adds it and records the install manifest).
function(elaslam_install_units base hardening)
  elaslam_install_dirs("${CMAKE_INSTALL_PREFIX}")
  _elaslam_config_place()
  _elaslam_work_dir(work "${base}")
  file(READ "${hardening}" ELASLAM_HARDENING)
  set(out "")
  foreach(in IN LISTS ARGN)
    get_filename_component(name "${in}" NAME)
    string(REGEX REPLACE "\\.in$" "" name "${name}")
    configure_file("${in}" "${work}/units/${name}" @ONLY)
    list(APPEND out "${work}/units/${name}")
  endforeach()
  file(INSTALL DESTINATION "${ELASLAM_UNITDIR}" TYPE FILE
       PERMISSIONS OWNER_READ OWNER_WRITE GROUP_READ WORLD_READ FILES ${out})
  file(REMOVE_RECURSE "${work}")
endfunction()

# elaslam_install_etc(<work dir> <yaml header.in> <default yaml> <env file>): the
# deployment config (the header, then a copy of the default config) and the
# services' environment file, into ELASLAM_ETCDIR.
function(elaslam_install_etc base header yaml env)
  elaslam_install_dirs("${CMAKE_INSTALL_PREFIX}")
  _elaslam_work_dir(work "${base}")
  configure_file("${header}" "${work}/etc/elaslam.yaml.head" @ONLY)
  file(READ "${work}/etc/elaslam.yaml.head" head)
  file(READ "${yaml}" body)
  file(WRITE "${work}/etc/elaslam.yaml" "${head}\n${body}")
  file(INSTALL DESTINATION "${ELASLAM_ETCDIR}" TYPE FILE
       PERMISSIONS OWNER_READ OWNER_WRITE GROUP_READ WORLD_READ
       FILES "${work}/etc/elaslam.yaml" "${env}")
  file(REMOVE_RECURSE "${work}")
endfunction()

# elaslam_install_pc(<work dir> <elaslam.pc.in>): the pkg-config file of the
# libraries (component dev) for CMAKE_INSTALL_PREFIX, into <prefix>/<libdir>/pkgconfig.
# Absolute paths, not ${pcfiledir}: the prefix /usr must be recognised (below).
function(elaslam_install_pc base template)
  string(REGEX REPLACE "(.)/+$" "\\1" prefix "${CMAKE_INSTALL_PREFIX}")
  foreach(d LIBDIR INCLUDEDIR)
    if(IS_ABSOLUTE "${ELASLAM_REL_${d}}")
      set(ELASLAM_PC_${d} "${ELASLAM_REL_${d}}")
    else()
      set(ELASLAM_PC_${d} "\${prefix}/${ELASLAM_REL_${d}}")
    endif()
  endforeach()
  set(ELASLAM_PC_PREFIX "${prefix}")
  # -isystem: the generated message headers do not pass -Wpedantic (lcm-gen's hash
  # code), as the build's own SYSTEM include of them and CMake's imported targets say.
  # None for /usr/include, where the compiler looks anyway (and where -isystem would
  # break GCC's #include_next).
  set(incdir "${ELASLAM_REL_INCLUDEDIR}")
  if(NOT IS_ABSOLUTE "${incdir}")
    set(incdir "${prefix}/${incdir}")
  endif()
  if(incdir STREQUAL "/usr/include")
    set(ELASLAM_PC_CFLAGS "")
  else()
    set(ELASLAM_PC_CFLAGS "-isystem \${includedir}")
  endif()
  _elaslam_work_dir(work "${base}")
  configure_file("${template}" "${work}/elaslam.pc" @ONLY)
  set(libdir "${ELASLAM_REL_LIBDIR}")
  if(NOT IS_ABSOLUTE "${libdir}")
    set(libdir "${prefix}/${libdir}")
  endif()
  file(INSTALL DESTINATION "${libdir}/pkgconfig" TYPE FILE
       PERMISSIONS OWNER_READ OWNER_WRITE GROUP_READ WORLD_READ FILES "${work}/elaslam.pc")
  file(REMOVE_RECURSE "${work}")
endfunction()
