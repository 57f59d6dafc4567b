set terminal pngcairo size 1400,1000
set output 'bench/results/paths_to_error_zen5_s32_all/paths_to_error.png'
set datafile separator ','
set logscale xy
set xlabel 'paths per probe'
set ylabel 'p95 per-axis irradiance error'
set key top right font ',8'
set grid
scenes = system("tail -n +2 'bench/results/paths_to_error_zen5_s32_all/paths_to_error.csv' | cut -d, -f1 | awk '!s[$0]++' | tr '\\n' ' '")
methods = system("tail -n +2 'bench/results/paths_to_error_zen5_s32_all/paths_to_error.csv' | cut -d, -f2 | awk '!s[$0]++' | tr '\\n' ' '")
n = words(scenes)
set multiplot layout (n + 1) / 2, 2
do for [sc in scenes] {
  set title sc
  plot for [m in methods] 'bench/results/paths_to_error_zen5_s32_all/paths_to_error.csv' using ((strcol(1) eq sc && strcol(2) eq m) ? $4 : 1/0):8 with linespoints title m, 0.05 with lines dt 2 title 'p95 target'
}
unset multiplot
