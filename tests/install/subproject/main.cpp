#include <peelcd/core/detector.h>
int main() { return 0; }
