# Holds the repository to standing alone (issue 44 §1): whoever clones it gets nothing else, so no
# file may send the reader to a place outside the tree. Everything a reader needs is inside:
# sources of values in docs/references.md, test reference values in docs/test-references.md, the
# mathematics in docs/design.md. Run by the tests repository_stands_alone and
# repository_stands_alone_rejects:
#   cmake -DROOT=<source tree> -P cmake/check_standalone.cmake
#
# Flags, in every file under ROOT:
#   - the relative path up into the notes folder that sat beside the repository while the project
#     was built (two dots, a slash, "shared");
#   - absolute paths into that workplace (a slash, "work", a slash);
#   - symbolic links whose target is absolute or leaves the tree.
# Skipped: .git/; what .gitignore keeps out of a clone (build trees build*/ and out/ at the top,
# __pycache__/, editor swap files), since those may hold absolute paths legitimately; binary files
# (by extension); and tests/data/standalone_violation/, the fixture that shows this check reports
# a violation (it is checked on its own, as ROOT, by repository_stands_alone_rejects).
# Reports every hit as <path>:<line>: ... (SEND_ERROR), then fails with their count.
cmake_minimum_required(VERSION 3.20)
if(NOT ROOT)
  message(FATAL_ERROR "usage: cmake -DROOT=<source tree> -P check_standalone.cmake")
endif()
get_filename_component(ROOT "${ROOT}" ABSOLUTE)
if(NOT IS_DIRECTORY "${ROOT}")
  message(FATAL_ERROR "check_standalone: ${ROOT} is not a directory")
endif()

# The needles are assembled from parts so that this file does not contain them and need not be
# skipped.
string(CONCAT _needle_notes ".." "/" "shared")
string(CONCAT _needle_workplace "/" "work" "/")
set(_needles "${_needle_notes}" "${_needle_workplace}")
set(_why0 "the notes folder outside the repository: put what the reader needs in docs/ and cite the primary source (docs/references.md)")
set(_why1 "an absolute path into the development workplace: use a path relative to the repository root")

# Extensions of binary files: not text, nothing to read.
set(_binary_ext png jpg jpeg gif bmp ico pdf gz tgz xz bz2 zip 7z tar mat o a so dylib dll exe bin
                pyc woff woff2 ttf otf)

file(GLOB_RECURSE _files LIST_DIRECTORIES false RELATIVE "${ROOT}" "${ROOT}/*")
list(SORT _files)
set(_errors 0)
set(_checked 0)
foreach(_file IN LISTS _files)
  if(_file MATCHES "^\\.git/" OR _file MATCHES "^(build[^/]*|out)/" OR
     _file MATCHES "(^|/)__pycache__/" OR _file MATCHES "\\.sw[a-p]$" OR
     _file MATCHES "^tests/data/standalone_violation/")
    continue()
  endif()
  set(_path "${ROOT}/${_file}")
  if(IS_SYMLINK "${_path}")
    file(READ_SYMLINK "${_path}" _target)
    get_filename_component(_dir "${_path}" DIRECTORY)
    get_filename_component(_resolved "${_target}" ABSOLUTE BASE_DIR "${_dir}")
    string(LENGTH "${ROOT}/" _rootlen)
    string(LENGTH "${_resolved}" _reslen)
    set(_inside FALSE)
    if(_reslen GREATER_EQUAL _rootlen)
      string(SUBSTRING "${_resolved}" 0 ${_rootlen} _head)
      if(_head STREQUAL "${ROOT}/")
        set(_inside TRUE)
      endif()
    endif()
    if(IS_ABSOLUTE "${_target}" OR NOT _inside)
      message(SEND_ERROR "${_file}: symbolic link to ${_target}, outside the repository")
      math(EXPR _errors "${_errors} + 1")
    endif()
    continue()
  endif()
  get_filename_component(_ext "${_file}" LAST_EXT)
  string(TOLOWER "${_ext}" _ext)
  string(REGEX REPLACE "^\\." "" _ext "${_ext}")
  if(_ext IN_LIST _binary_ext)
    continue()
  endif()
  math(EXPR _checked "${_checked} + 1")
  file(READ "${_path}" _text)
  foreach(_k RANGE 1)
    list(GET _needles ${_k} _needle)
    set(_rest "${_text}")
    set(_line 1)
    while(TRUE)
      string(FIND "${_rest}" "${_needle}" _at)
      if(_at EQUAL -1)
        break()
      endif()
      # The line of the hit: 1 + the newlines before it.
      string(SUBSTRING "${_rest}" 0 ${_at} _before)
      string(REGEX MATCHALL "\n" _newlines "${_before}")
      list(LENGTH _newlines _n)
      math(EXPR _line "${_line} + ${_n}")
      message(SEND_ERROR "${_file}:${_line}: refers outside the repository (\"${_needle}\"), ${_why${_k}}")
      math(EXPR _errors "${_errors} + 1")
      string(LENGTH "${_needle}" _len)
      math(EXPR _from "${_at} + ${_len}")
      string(SUBSTRING "${_rest}" ${_from} -1 _rest)
    endwhile()
  endforeach()
endforeach()
if(_errors GREATER 0)
  message(FATAL_ERROR "standalone: ${_errors} reference(s) outside the repository in ${_checked} file(s) read")
endif()
message(STATUS "standalone: ${_checked} file(s) read under ${ROOT}, none refers outside it")
