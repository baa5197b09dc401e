#include <peelcd/core/image/detector.h>
int main() { return 0; }
