set terminal pngcairo size 1100,700
set output 'bench/results/speed_vs_error_zen5_s33/speed_vs_error.png'
set datafile separator ','
set logscale xy
set xlabel 'bake GPU time (ms)'
set ylabel 'relative RMSE of probe irradiance'
set key outside right
set grid
scenes = system("tail -n +2 'bench/results/speed_vs_error_zen5_s33/speed_vs_error.csv' | cut -d, -f1 | sort -u | tr '\\n' ' '")
plot for [s in scenes] for [m in 'path volume'] for [b in '1 3'] 'bench/results/speed_vs_error_zen5_s33/speed_vs_error.csv' using ((strcol(1) eq s && strcol(3) eq m && strcol(4) eq b) ? $7 : 1/0):9 with linespoints title s.' '.m.' '.b.' bnc'
