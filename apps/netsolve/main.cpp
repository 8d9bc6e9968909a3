// netsolve: the executable; the command line itself is command.cpp (library netdem_netsolve_cli).
#include "command.hpp"

int main(int argc, char** argv) { return netsolve_command(argc, argv); }
