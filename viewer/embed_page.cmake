# SPDX-License-Identifier: Apache-2.0
# cmake -DIN=page.html -DOUT=page.cpp -P embed_page.cmake: the page as a C++ string.
file(READ ${IN} PAGE)
string(FIND "${PAGE}" ")elaslam_page\"" CLASH)
if(NOT CLASH EQUAL -1)
  message(FATAL_ERROR "${IN} contains the raw-string delimiter )elaslam_page\"")
endif()
file(WRITE ${OUT} "// Generated from viewer/web/index.html by embed_page.cmake.\nnamespace elaslam::viewer {\nextern const char* const kIndexHtml;\nconst char* const kIndexHtml = R\"elaslam_page(${PAGE})elaslam_page\";\n}\n")
