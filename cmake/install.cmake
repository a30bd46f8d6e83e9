# Deployment (docs/deployment.md). `cmake --install build --prefix /usr/local`
# puts the program in bin/, the units in lib/systemd/system/ (systemd reads
# /usr/local/lib/systemd/system too), the service's configs in etc/rigctl/,
# every shipped config (with the demand files its cases name) in
# share/rigctl/config/ and the docs in share/doc/rigctl/.
#
# The configuration directory and the controller's unit are decided at
# install time, not at configure time, because --prefix (and CPack's /usr)
# may differ from the configured prefix: under /usr the configs go to /etc
# (the FHS place, as Debian packages do), elsewhere to PREFIX/etc. The unit is
# written with the paths actually installed to.
install(TARGETS rigctl RUNTIME DESTINATION bin)
install(FILES systemd/lcm-logger.service DESTINATION lib/systemd/system)
file(GLOB RIGCTL_SHIPPED_CONFIGS ${PROJECT_SOURCE_DIR}/config/*.yaml ${PROJECT_SOURCE_DIR}/config/*.csv)
install(FILES ${RIGCTL_SHIPPED_CONFIGS} DESTINATION share/rigctl/config)
install(CODE "set(RIGCTL_SOURCE_DIR \"${PROJECT_SOURCE_DIR}\")")
install(CODE [[
  set(RIGCTL_PREFIX "${CMAKE_INSTALL_PREFIX}")
  if(RIGCTL_PREFIX STREQUAL "/usr")
    set(RIGCTL_SYSCONFDIR /etc)
  else()
    set(RIGCTL_SYSCONFDIR "${RIGCTL_PREFIX}/etc")
  endif()
  file(INSTALL "${RIGCTL_SOURCE_DIR}/config/quarter_car.yaml" "${RIGCTL_SOURCE_DIR}/config/pneumatic_rotary.yaml"
               "${RIGCTL_SOURCE_DIR}/config/half_car.yaml"
       DESTINATION "${RIGCTL_SYSCONFDIR}/rigctl")  # file(INSTALL) adds DESTDIR itself
  configure_file("${RIGCTL_SOURCE_DIR}/systemd/rigctl.service.in"
                 "$ENV{DESTDIR}${RIGCTL_PREFIX}/lib/systemd/system/rigctl.service" @ONLY)
  message(STATUS "Installing: $ENV{DESTDIR}${RIGCTL_PREFIX}/lib/systemd/system/rigctl.service")
]])
install(FILES README.md SAFETY.md DESTINATION share/doc/rigctl)
install(DIRECTORY docs/ DESTINATION share/doc/rigctl)
install(FILES LICENSE DESTINATION share/doc/rigctl RENAME copyright)

# The Debian package: `cmake --build build --target package` writes
# build/rigctl_<version>_amd64.deb. Installed under /usr with DESTDIR so the
# install-time paths above see the package's real prefix; dpkg-shlibdeps
# (Debian's dpkg-dev) names the run-time libraries' packages, so
# `apt install ./rigctl_*.deb` pulls exactly what the program links.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME rigctl)
set(CPACK_PACKAGE_VENDOR "the rigctl developers")
set(CPACK_PACKAGE_CONTACT "the rigctl developers <rigctl@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "real-time HIL controller for servo-hydraulic and pneumatic test rigs")
set(CPACK_PACKAGE_DESCRIPTION "One program runs a 2.5 ms control loop against Modbus/CANopen rig hardware or a simulated plant, publishes telemetry over LCM and Foxglove, logs every run, and diagnoses model discrepancies. Ships the controller's systemd unit (operator mode) and an LCM logger unit.")
set(CPACK_SET_DESTDIR ON)
set(CPACK_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)  # rigctl_<version>_<arch>.deb
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# lcm-logger.service runs Debian's lcm-logger; the plots need matplotlib.
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "liblcm-bin")
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "python3-matplotlib, python3-numpy")
# The service's configs are the site's to edit: dpkg keeps local changes.
set(RIGCTL_CONFFILES "${PROJECT_BINARY_DIR}/debian/conffiles")
file(WRITE "${RIGCTL_CONFFILES}" "/etc/rigctl/quarter_car.yaml\n/etc/rigctl/pneumatic_rotary.yaml\n/etc/rigctl/half_car.yaml\n")
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA "${RIGCTL_CONFFILES}")
include(CPack)
