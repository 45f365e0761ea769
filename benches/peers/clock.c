/* The core's clock, for turning times into cycles on a machine without hardware counters
 * (docs/src/engineering/floor.md, "The earlier analyses"): a chain of dependent
 * integer adds retires one per cycle. Not built by cargo or CI.
 *
 *   gcc -O2 -o /tmp/clock benches/peers/clock.c && /tmp/clock
 */
#include <stdio.h>
#include <time.h>
int main(){
  struct timespec a,b; long n=2000000000; unsigned long x=1;
  clock_gettime(CLOCK_MONOTONIC,&a);
  for(long i=0;i<n;i++){ __asm__ volatile("add $1, %0\n\tadd $1, %0\n\tadd $1, %0\n\tadd $1, %0" : "+r"(x)); }
  clock_gettime(CLOCK_MONOTONIC,&b);
  double t=(b.tv_sec-a.tv_sec)+(b.tv_nsec-a.tv_nsec)*1e-9;
  printf("%.3f GHz (x=%lu)\n", 4.0*n/t/1e9, x);
}
