// Hosts the precompiled headers every jointlab library reuses (CMakeLists.txt); no code.
