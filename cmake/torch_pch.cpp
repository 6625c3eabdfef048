// The translation unit that owns the shared LibTorch precompiled header (cmake/torch_pch.cmake):
// CMake builds the header from it; the file itself has nothing to compile.
