#pragma once
// The whole demsolve command line as a function (command.cpp), in the library netdem_demsolve_cli that the
// executable (main.cpp) and the Python module (python/_netdem.cpp) both link. It may be called more
// than once in a process: each call starts from a fresh run state (reset_run_state, output.hpp).

/// Parses argv (argv[0] the program name, argv[1] the subcommand), runs it and returns the exit
/// status (0 ok, 1 run error, 2 command-line error, 3 finished but untrustworthy: README.md).
int demsolve_command(int argc, char** argv);
