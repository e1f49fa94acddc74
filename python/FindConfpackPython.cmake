# Looks for what the Python module needs (an interpreter with its headers, and pybind11) as
# CONFPACK_PYTHON asks, and sets CONFPACK_PYTHON_FOUND. Debian's pybind11 (pybind11-dev) is built
# for Debian's interpreter: where another python3 comes first on PATH (pyenv, conda), pass
# -DPython_EXECUTABLE=/usr/bin/python3.
set(CONFPACK_PYTHON_FOUND OFF)
if(CONFPACK_SANITIZE OR CONFPACK_FUZZ)
  # An ASan-instrumented extension loads only into an instrumented interpreter.
  message(STATUS "confpack Python module: not built with CONFPACK_SANITIZE or CONFPACK_FUZZ")
elseif(NOT CONFPACK_PYTHON STREQUAL "OFF")
  if(CONFPACK_PYTHON STREQUAL "ON")
    set(_confpack_required REQUIRED)
  endif()
  find_package(Python 3.9 COMPONENTS Interpreter Development.Module ${_confpack_required})
  if(Python_FOUND)
    # pybind11 takes the interpreter found above (its FindPython mode).
    set(PYBIND11_FINDPYTHON ON)
    find_package(pybind11 2.6 CONFIG ${_confpack_required})
  endif()
  if(Python_FOUND AND pybind11_FOUND)
    set(CONFPACK_PYTHON_FOUND ON)
    set(CMAKE_POSITION_INDEPENDENT_CODE ON)
    message(STATUS "confpack Python module: built for ${Python_EXECUTABLE} (${Python_VERSION})")
  else()
    message(STATUS "confpack Python module: not built (needs pybind11-dev and python3-dev; "
                   "CONFPACK_PYTHON=ON makes this an error)")
  endif()
endif()
