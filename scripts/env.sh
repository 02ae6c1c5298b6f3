#!/usr/bin/env bash
# The workspace environment, in one place (used by the Makefile, usable by hand).
#
#   scripts/env.sh <command...>          run <command> with the venv active and install/setup.bash
#                                        sourced, e.g. scripts/env.sh python -m tumble_ros
#   scripts/env.sh --build <command...>  run <command> in the build environment: the venv active and
#                                        AMENT_PREFIX_PATH = CMAKE_PREFIX_PATH = the venv prefix, as
#                                        colcon needs with the PyPI ROS wheels; install/ not sourced
#   source scripts/env.sh                set up the current bash shell (run environment)
#
# Run environment: after `source install/setup.bash`, AMENT_PREFIX_PATH names only the workspace's
# packages, not the venv (which has no colcon local_setup files): the venv prefix is appended again
# so that ament index lookups (message definitions, share/ of geometry_msgs, ...) find the ROS
# packages installed by pip. The venv is .venv at the repository root (override: TUMBLE_ROS_VENV).

_tumble_ros_env() {
    local root venv mode=run
    root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
    venv="${TUMBLE_ROS_VENV:-$root/.venv}"
    if [[ "${1:-}" == --build ]]; then
        mode=build
    fi
    if [[ ! -f "$venv/bin/activate" ]]; then
        echo "scripts/env.sh: no venv at $venv: run 'make setup' first" >&2
        return 1
    fi
    if [[ "$mode" == run && ! -f "$root/install/setup.bash" ]]; then
        echo "scripts/env.sh: no $root/install/setup.bash: run 'make setup' first" >&2
        return 1
    fi
    # shellcheck disable=SC1091
    source "$venv/bin/activate" || return 1
    if [[ "$mode" == build ]]; then
        # DESIGN quirk 1: the ROS CMake packages are found through these two variables only.
        # A ROS workspace sourced in the calling shell must not leak into the build.
        export AMENT_PREFIX_PATH="$VIRTUAL_ENV" CMAKE_PREFIX_PATH="$VIRTUAL_ENV"
        unset COLCON_PREFIX_PATH PYTHONPATH
        return 0
    fi
    # colcon's setup scripts are not written for `set -u`.
    local nounset=0
    [[ $- == *u* ]] && nounset=1 && set +u
    # shellcheck disable=SC1091
    source "$root/install/setup.bash" || return 1
    ((nounset)) && set -u
    # Discovery stays on this machine unless the caller chose otherwise (docs/ros.md "Isolation").
    export ROS_AUTOMATIC_DISCOVERY_RANGE="${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}"
    case ":${AMENT_PREFIX_PATH:-}:" in
        *":$VIRTUAL_ENV:"*) ;;
        *) export AMENT_PREFIX_PATH="${AMENT_PREFIX_PATH:+$AMENT_PREFIX_PATH:}$VIRTUAL_ENV" ;;
    esac
    return 0
}

if [[ "${BASH_SOURCE[0]}" != "$0" ]]; then
    # Sourced: set up the calling shell.
    _tumble_ros_env "$@"
    unset -f _tumble_ros_env
    return
fi

set -eo pipefail
_tumble_ros_env "$@"
[[ "${1:-}" == --build ]] && shift
if [[ $# -eq 0 ]]; then
    echo "usage: scripts/env.sh [--build] <command...>  |  source scripts/env.sh" >&2
    exit 2
fi
exec "$@"
