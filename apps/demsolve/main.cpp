// demsolve: the executable; the command line itself is command.cpp (library netdem_demsolve_cli).
#include "command.hpp"

int main(int argc, char** argv) { return demsolve_command(argc, argv); }
