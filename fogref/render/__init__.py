"""Mitsuba glue: variant and LLVM set-up, scene loading, EXR layers."""
