# Debian packages by CPack's DEB generator (`make deb`: cpack in the build
# directory, docs/install.md): one package per install component of
# cmake/install.cmake,
#   pathd      the daemon, pathctl, bundled maps, /etc/pathd/pathd.yaml and
#              the systemd unit; its dependencies are the shared libraries
#              the binaries link, found by dpkg-shlibdeps
#   pathd-dev  the C++ client package (find_package(pathd)) and the protos
# installed under /usr (the config in /etc; see cmake/install.cmake).
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME pathd)
set(CPACK_PACKAGE_VENDOR pathd)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "gRPC path-planning daemon over named 2D grid maps")
set(CPACK_PACKAGE_CONTACT "pathd maintainers <maintainers@pathd.invalid>")
set(CPACK_RESOURCE_FILE_LICENSE ${PROJECT_SOURCE_DIR}/LICENSE)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
# With DESTDIR staging CPack installs to CPACK_INSTALL_PREFIX (else the
# build's CMAKE_INSTALL_PREFIX, /usr/local).
set(CPACK_INSTALL_PREFIX /usr)
# The install rules place /etc/pathd themselves when the prefix is /usr,
# which needs the prefix to be /usr at install time: DESTDIR staging.
set(CPACK_SET_DESTDIR ON)
set(CPACK_PACKAGE_DIRECTORY ${PROJECT_BINARY_DIR}/packages)

set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL daemon dev)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION net)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# Release binaries without their symbol tables (no debug info to split off).
set(CPACK_STRIP_FILES ON)

set(CPACK_DEBIAN_DAEMON_PACKAGE_NAME pathd)
set(CPACK_COMPONENT_DAEMON_DESCRIPTION
    "gRPC path-planning daemon (pathd), its command-line client (pathctl), example maps and a systemd unit")
# /etc/pathd/pathd.yaml is the operator's: an upgrade keeps their edits.
file(WRITE ${PROJECT_BINARY_DIR}/packaging/deb/conffiles "/etc/pathd/pathd.yaml\n")
set(CPACK_DEBIAN_DAEMON_PACKAGE_CONTROL_EXTRA ${PROJECT_BINARY_DIR}/packaging/deb/conffiles)

set(CPACK_DEBIAN_DEV_PACKAGE_NAME pathd-dev)
set(CPACK_COMPONENT_DEV_DESCRIPTION
    "C++ client library of pathd (static, find_package(pathd)) and its .proto files")
# Static libraries: the consumer links the same gRPC, protobuf and Abseil.
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS "libgrpc++-dev, libprotobuf-dev, libabsl-dev")
set(CPACK_DEBIAN_DEV_PACKAGE_ARCHITECTURE amd64)

include(CPack)
