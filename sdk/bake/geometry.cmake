# Footprint triangulation and building extrusion, included by sdk/bake/CMakeLists.txt.
# triangulate.cpp is the module's only CGAL translation unit (about 16 s and 730 MB each).
set(BLVD_BAKE_GEOMETRY_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/triangulate.cpp
  ${CMAKE_CURRENT_LIST_DIR}/extrude.cpp
  ${CMAKE_CURRENT_LIST_DIR}/depth_mesh.cpp)
