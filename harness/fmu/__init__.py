"""The generator FMU: variable list (spec), code generation, build, and the fmpy runner."""
