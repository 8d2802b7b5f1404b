# Installation and the Debian package.
#
#   cmake --install build --prefix /usr/local      # into a prefix
#   (cd build && cpack -G DEB)                     # build/canopen-gateway_<version>_<arch>.deb
#
# Both give <prefix>/bin/{canopen-gateway,canopen-eds,canopen-sim},
# <prefix>/share/canopen-gateway/{web,eds,gateway.example.yaml},
# <prefix>/lib/systemd/system/canopen-gateway.service and
# <prefix>/share/doc/canopen-gateway. The installed gateway finds its
# dashboard as <prefix>/share/canopen-gateway/web (gateway/app/process.cpp).
# The package (prefix /usr) adds /etc/canopen-gateway/gateway.yaml as a
# conffile, the service's system user and the unit enabled and started
# (deploy/debian/). cpack only installs what is built: build first.
include(GNUInstallDirs)

set(GW_NAME canopen-gateway)
set(GW_DATA_REL ${CMAKE_INSTALL_DATADIR}/${GW_NAME})
set(GW_DOC_REL ${CMAKE_INSTALL_DATAROOTDIR}/doc/${GW_NAME})  # not DOCDIR: that is named after the project
# Directories made by the install (and so in the package) are 0755 whatever
# the umask of whoever builds.
set(CMAKE_INSTALL_DEFAULT_DIRECTORY_PERMISSIONS
    OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ GROUP_EXECUTE WORLD_READ WORLD_EXECUTE)

set(GW_PROGRAMS canopen-gateway canopen-eds canopen-sim)
install(TARGETS ${GW_PROGRAMS} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# Full RELRO, as Debian links its packages: relocations resolved at start,
# then read-only.
foreach(prog ${GW_PROGRAMS})
  target_link_options(${prog} PRIVATE LINKER:-z,relro LINKER:-z,now)
endforeach()
# The vendored library's licence and notes are in the copyright file.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/web/ DESTINATION ${GW_DATA_REL}/web
        PATTERN README.md EXCLUDE PATTERN LICENSE EXCLUDE)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/deploy/eds/ DESTINATION ${GW_DATA_REL}/eds)
install(FILES ${PROJECT_SOURCE_DIR}/README.md ${PROJECT_SOURCE_DIR}/deploy/debian/copyright DESTINATION ${GW_DOC_REL})
if(EXISTS ${PROJECT_SOURCE_DIR}/docs)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION ${GW_DOC_REL}/docs)
endif()

# Written at install time, when the prefix is known: the unit names the
# binary by its installed path, and the example configuration names the
# installed EDS files (deploy/gateway.example.yaml says /usr/share/..., the
# package's place; another prefix replaces it). The unit goes to lib/, not
# LIBDIR: no multiarch for units.
install(CODE "
  set(prefix \"\${CMAKE_INSTALL_PREFIX}\")
  set(dest \"\$ENV{DESTDIR}\${prefix}\")
  set(perm FILE_PERMISSIONS OWNER_READ OWNER_WRITE GROUP_READ WORLD_READ)
  set(GW_BINDIR \"\${prefix}/${CMAKE_INSTALL_BINDIR}\")
  set(GW_DATADIR \"\${prefix}/${GW_DATA_REL}\")
  set(GW_DOCDIR \"\${prefix}/${GW_DOC_REL}\")
  configure_file(\"${PROJECT_SOURCE_DIR}/deploy/canopen-gateway.service.in\"
                 \"\${dest}/lib/systemd/system/${GW_NAME}.service\" @ONLY \${perm})
  file(READ \"${PROJECT_SOURCE_DIR}/deploy/gateway.example.yaml\" yaml)
  string(REPLACE \"/usr/share/${GW_NAME}/\" \"\${GW_DATADIR}/\" yaml \"\${yaml}\")
  file(WRITE \"\${dest}/${GW_DATA_REL}/gateway.example.yaml\" \"\${yaml}\")
  file(CHMOD \"\${dest}/${GW_DATA_REL}/gateway.example.yaml\" \${perm})
  foreach(f lib/systemd/system/${GW_NAME}.service ${GW_DATA_REL}/gateway.example.yaml)
    message(STATUS \"Installing: \${dest}/\${f}\")
    list(APPEND CMAKE_INSTALL_MANIFEST_FILES \"\${dest}/\${f}\")
  endforeach()
")

# Manual pages: each program's --help with a header (cmake/manpage.cmake)
# and the sections in deploy/man/NAME.extra.in.
set(man_summary_canopen-gateway "CANopen-to-IP gateway (MQTT, REST, WebSocket)")
set(man_summary_canopen-eds "check EDS/DCF files with the gateway's rules, show their dictionary")
set(man_summary_canopen-sim "simulated CANopen devices on a SocketCAN interface")
foreach(prog ${GW_PROGRAMS})
  install(CODE "
    set(prefix \"\${CMAKE_INSTALL_PREFIX}\")
    set(GW_DATADIR \"\${prefix}/${GW_DATA_REL}\")
    set(GW_DOCDIR \"\${prefix}/${GW_DOC_REL}\")
    configure_file(\"${PROJECT_SOURCE_DIR}/deploy/man/${prog}.extra.in\" \"${PROJECT_BINARY_DIR}/man/${prog}.extra\" @ONLY)
    file(READ \"${PROJECT_BINARY_DIR}/man/${prog}.extra\" MAN_EXTRA)
    set(MAN_PROGRAM \"$<TARGET_FILE:${prog}>\")
    set(MAN_NAME ${prog})
    set(MAN_SUMMARY \"${man_summary_${prog}}\")
    set(MAN_VERSION ${PROJECT_VERSION})
    set(MAN_OUT \"\$ENV{DESTDIR}\${prefix}/${CMAKE_INSTALL_MANDIR}/man1/${prog}.1.gz\")
    file(MAKE_DIRECTORY \"\$ENV{DESTDIR}\${prefix}/${CMAKE_INSTALL_MANDIR}/man1\")
    include(\"${PROJECT_SOURCE_DIR}/cmake/manpage.cmake\")
    message(STATUS \"Installing: \${MAN_OUT}\")
    list(APPEND CMAKE_INSTALL_MANIFEST_FILES \"\${MAN_OUT}\")
  ")
endforeach()

# ---- the Debian package -------------------------------------------------------
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME ${GW_NAME})
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "CANopen-to-IP gateway (MQTT, REST, WebSocket)")
set(CPACK_PACKAGE_DESCRIPTION
"canopen-gateway connects CANopen networks on SocketCAN interfaces to IP:
it publishes PDOs, heartbeats, EMCYs and node states to an MQTT broker,
answers SDO and NMT requests over MQTT and a REST API, streams events over
WebSocket and serves a web dashboard. It boots and configures nodes from
their EDS/DCF files.
.
As installed, the service runs a simulated network (no CAN hardware needed)
and serves the dashboard on http://127.0.0.1:8080/; the configuration is
/etc/canopen-gateway/gateway.yaml. Includes canopen-eds (checks EDS/DCF
files) and canopen-sim (simulated devices on a SocketCAN interface).")
set(CANOPEN_DEB_MAINTAINER "canopen-gateway maintainers <maintainers@users.noreply.h-seed-cc40767a.example>"
    CACHE STRING "Maintainer field of the Debian package")
set(CPACK_DEBIAN_PACKAGE_MAINTAINER "${CANOPEN_DEB_MAINTAINER}")
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)  # canopen-gateway_<version>_<arch>.deb
set(CPACK_DEBIAN_PACKAGE_SECTION net)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
# Shared libraries found by dpkg-shlibdeps (dpkg-dev); adduser for postinst.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "adduser")  # deb-systemd-helper: essential init-system-helpers
# The service publishes to a broker on localhost as shipped.
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "mosquitto")
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "mosquitto-clients, can-utils")
# Binaries without debug info: smaller, and stripping is faster than
# compressing it. xz as Debian packages are, on every core (about 1.4 MB
# and 5 s here; gzip: 2.3 MB, 2 s faster).
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_COMPRESSION_TYPE xz)
set(CPACK_THREADS 0)
set(CPACK_INSTALL_DEFAULT_DIRECTORY_PERMISSIONS ${CMAKE_INSTALL_DEFAULT_DIRECTORY_PERMISSIONS})

set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
    ${PROJECT_SOURCE_DIR}/deploy/debian/postinst
    ${PROJECT_SOURCE_DIR}/deploy/debian/prerm
    ${PROJECT_SOURCE_DIR}/deploy/debian/postrm
    ${PROJECT_SOURCE_DIR}/deploy/debian/conffiles)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
# Package-only files, added to the staged tree: the conffile, the Debian
# changelog, lintian overrides (cmake/deb-staging.cmake).
set(CPACK_PRE_BUILD_SCRIPTS ${PROJECT_SOURCE_DIR}/cmake/deb-staging.cmake)
set(CPACK_CANOPEN_DATA_REL ${GW_DATA_REL})  # CPACK_*: what the script sees
set(CPACK_CANOPEN_DOC_REL ${GW_DOC_REL})
set(CPACK_CANOPEN_SOURCE_DIR ${PROJECT_SOURCE_DIR})
# `package_source`: the sources without build trees, git or npm data.
set(CPACK_SOURCE_GENERATOR TGZ)
set(CPACK_SOURCE_PACKAGE_FILE_NAME ${GW_NAME}-${PROJECT_VERSION})
set(CPACK_SOURCE_IGNORE_FILES "/build[^/]*/" "/\\\\.git/" "/node_modules/" "\\\\.swp$")  # regexes, escaped twice
include(CPack)
