set terminal pngcairo size 1100,700
set output 'bench/results/paths_to_error/paths_to_error.png'
set datafile separator ','
set logscale xy
set xlabel 'paths per probe'
set ylabel 'p95 per-axis irradiance error'
set key outside right
set grid
rows = system("tail -n +2 'bench/results/paths_to_error/paths_to_error.csv' | cut -d, -f1,2 | sort -u | tr '\\n' ' '")
plot for [r in rows] 'bench/results/paths_to_error/paths_to_error.csv' using ((strcol(1).','.strcol(2)) eq r ? $4 : 1/0):8 with linespoints title r, 0.05 with lines dt 2 title 'p95 target'
