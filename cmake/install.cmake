# What `cmake --install build [--prefix DIR] [--component C]`, `make install`
# and the packages of `make deb` (cmake/packaging.cmake) install. Two
# components:
#   daemon  bin/pathd, bin/pathctl, the bundled maps in share/pathd/maps
#           (pathd serves them when no --map_dir is given), the config in
#           etc/pathd/pathd.yaml (/etc/pathd when the prefix is /usr) and the
#           systemd unit in lib/systemd/system/pathd.service
#   dev     the C++ client: pathd::client and pathd::proto (static libraries),
#           their headers under include/pathd, and lib/cmake/pathd for
#           find_package(pathd) (examples/cpp_client)
# docs/install.md has the layout and how to use each part.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

# `make install` / the install target installs what was built rather than
# building everything first (the tests and benchmarks need not exist); the
# Makefile's install and deb targets build the installed targets themselves.
set(CMAKE_SKIP_INSTALL_ALL_DEPENDENCY ON)

# ---- daemon ----
install(TARGETS pathd pathctl RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT daemon)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/maps/ DESTINATION ${CMAKE_INSTALL_DATADIR}/pathd/maps
        COMPONENT daemon FILES_MATCHING PATTERN "*.map" PATTERN "*.yaml" PATTERN "*.pgm")

# The installed config is examples/pathd.yaml with map_dir left unset, so
# pathd serves the bundled maps unless the operator names a folder.
file(READ ${PROJECT_SOURCE_DIR}/examples/pathd.yaml PATHD_CONFIG_TEXT)
string(FIND "${PATHD_CONFIG_TEXT}" "\nmap_dir: \"\"\n" PATHD_MAP_DIR_LINE)
if(PATHD_MAP_DIR_LINE EQUAL -1)
  message(FATAL_ERROR "examples/pathd.yaml has no 'map_dir: \"\"' line for cmake/install.cmake to unset")
endif()
string(REPLACE "# pathd config file: `pathd --config=examples/pathd.yaml`."
       "# pathd config file, as installed (from examples/pathd.yaml): the systemd\n# unit runs `pathd --config=` this file."
       PATHD_CONFIG_TEXT "${PATHD_CONFIG_TEXT}")
string(REPLACE "\nmap_dir: \"\"\n"
       "\n# Unset here: the bundled maps of this install (PREFIX/share/pathd/maps,\n# /usr/share/pathd/maps for the .deb); \"\" = none.\n# map_dir: \"\"\n"
       PATHD_CONFIG_TEXT "${PATHD_CONFIG_TEXT}")
file(GENERATE OUTPUT ${PROJECT_BINARY_DIR}/packaging/pathd.yaml CONTENT "${PATHD_CONFIG_TEXT}")

# The config and the unit name absolute paths that depend on the prefix the
# install finally uses (`cmake --install --prefix`, CPack's /usr), so they are
# placed and written at install time: a /usr prefix keeps its config in /etc
# (Debian policy, as GNUInstallDirs' CMAKE_INSTALL_FULL_SYSCONFDIR says),
# any other prefix in PREFIX/etc. file(INSTALL) adds $DESTDIR itself and
# records the files in the install manifest.
install(CODE "
  if(CMAKE_INSTALL_PREFIX STREQUAL \"/usr\")
    set(PATHD_ETC \"/etc/pathd\")
  else()
    set(PATHD_ETC \"\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_SYSCONFDIR}/pathd\")
  endif()
  file(INSTALL DESTINATION \"\${PATHD_ETC}\" TYPE FILE
       FILES \"${PROJECT_BINARY_DIR}/packaging/pathd.yaml\")
  set(PATHD_BIN \"\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_BINDIR}\")
  configure_file(\"${PROJECT_SOURCE_DIR}/packaging/pathd.service.in\"
                 \"${PROJECT_BINARY_DIR}/packaging/pathd.service\" @ONLY)
  file(INSTALL DESTINATION \"\${CMAKE_INSTALL_PREFIX}/lib/systemd/system\" TYPE FILE
       FILES \"${PROJECT_BINARY_DIR}/packaging/pathd.service\")
" COMPONENT daemon)

# ---- dev: the C++ client package ----
# pathd::client's public header includes the generated pathd/v1 and
# grpc/health/v1 headers; nothing of pathd::core (client/CMakeLists.txt).
set_target_properties(pathd_client PROPERTIES EXPORT_NAME client)
set_target_properties(pathd_proto PROPERTIES EXPORT_NAME proto)
set_target_properties(pathd_path_codec PROPERTIES EXPORT_NAME path_codec)
set(PATHD_INCLUDE_DIR ${CMAKE_INSTALL_INCLUDEDIR}/pathd)
install(TARGETS pathd_client pathd_proto pathd_path_codec EXPORT pathdTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev
        INCLUDES DESTINATION ${PATHD_INCLUDE_DIR})
install(FILES ${PROJECT_SOURCE_DIR}/client/client.h
        DESTINATION ${PATHD_INCLUDE_DIR}/client COMPONENT dev)
install(FILES ${PROJECT_SOURCE_DIR}/proto/path_codec.h
        DESTINATION ${PATHD_INCLUDE_DIR}/proto COMPONENT dev)
foreach(name common map_service planner_service)
  install(FILES ${PROJECT_BINARY_DIR}/proto/pathd/v1/${name}.pb.h
                ${PROJECT_BINARY_DIR}/proto/pathd/v1/${name}.grpc.pb.h
          DESTINATION ${PATHD_INCLUDE_DIR}/pathd/v1 COMPONENT dev)
endforeach()
install(FILES ${PROJECT_BINARY_DIR}/proto/grpc/health/v1/health.pb.h
              ${PROJECT_BINARY_DIR}/proto/grpc/health/v1/health.grpc.pb.h
        DESTINATION ${PATHD_INCLUDE_DIR}/grpc/health/v1 COMPONENT dev)
# The wire contract itself, for clients in other languages.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/proto/pathd/v1/ DESTINATION ${CMAKE_INSTALL_DATADIR}/pathd/proto/pathd/v1
        COMPONENT dev FILES_MATCHING PATTERN "*.proto")

set(PATHD_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/pathd)
install(EXPORT pathdTargets NAMESPACE pathd:: DESTINATION ${PATHD_CMAKE_DIR} COMPONENT dev)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/pathdConfig.cmake.in
  ${PROJECT_BINARY_DIR}/packaging/pathdConfig.cmake INSTALL_DESTINATION ${PATHD_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/packaging/pathdConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/packaging/pathdConfig.cmake
              ${PROJECT_BINARY_DIR}/packaging/pathdConfigVersion.cmake
        DESTINATION ${PATHD_CMAKE_DIR} COMPONENT dev)
