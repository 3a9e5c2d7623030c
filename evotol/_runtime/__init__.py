"""Runtime helpers with no physics in them (layer 0): BLAS threads, the parallel executor, Ctrl-C,
progress lines, output folders, the conformance-suite runner, keyword and file-kind checks."""
