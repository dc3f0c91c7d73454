# gnuplot script written by bench/bench.c; run in bench/out: gnuplot plots.gp
set terminal pngcairo size 900,560 font 'sans,11'
set output 'cornell.png'
set title 'cornell (128x128, median of seeds)'
set logscale xy
set format x '10^{%L}'
set format y '10^{%L}'
set xlabel 'render time (s)'
set ylabel 'relMSE'
set grid
set key outside right
plot 'cornell.dat' index 0 using 1:2 with linespoints lc rgb '#d62728' pt 5 title 'material', \
     'cornell.dat' index 1 using 1:2 with linespoints lc rgb '#1f77b4' pt 7 title 'light', \
     'cornell.dat' index 2 using 1:2 with linespoints lc rgb '#ff7f0e' pt 9 dt 2 title 'mix0.25', \
     'cornell.dat' index 3 using 1:2 with linespoints lc rgb '#9467bd' pt 11 dt 2 title 'mix0.5', \
     'cornell.dat' index 4 using 1:2 with linespoints lc rgb '#8c564b' pt 13 dt 2 title 'mix0.75', \
     'cornell.dat' index 5 using 1:2 with linespoints lc rgb '#2ca02c' pt 4 lw 2 title 'mis', \
     'cornell.dat' index 6 using 1:2 with linespoints lc rgb '#17becf' pt 6 lw 2 title 'mis-sobol', \
     'cornell.dat' index 7 using 1:2:(sprintf('q%d', $3)) with labels point pt 3 ps 1.5 lc rgb 'black' offset 0.8,0.6 font ',8' title 'POV-Ray', \
     'cornell.dat' index 8 using 1:2 with linespoints lc rgb '#000000' pt 2 dt 3 lw 2 title 'Mitsuba independent', \
     'cornell.dat' index 9 using 1:2 with linespoints lc rgb '#7f7f7f' pt 1 dt 3 lw 2 title 'Mitsuba multijitter'
reset
set output 'tiny-light.png'
set title 'tiny-light (128x128, median of seeds)'
set logscale xy
set format x '10^{%L}'
set format y '10^{%L}'
set xlabel 'render time (s)'
set ylabel 'relMSE'
set grid
set key outside right
plot 'tiny-light.dat' index 0 using 1:2 with linespoints lc rgb '#d62728' pt 5 title 'material', \
     'tiny-light.dat' index 1 using 1:2 with linespoints lc rgb '#1f77b4' pt 7 title 'light', \
     'tiny-light.dat' index 2 using 1:2 with linespoints lc rgb '#ff7f0e' pt 9 dt 2 title 'mix0.25', \
     'tiny-light.dat' index 3 using 1:2 with linespoints lc rgb '#9467bd' pt 11 dt 2 title 'mix0.5', \
     'tiny-light.dat' index 4 using 1:2 with linespoints lc rgb '#8c564b' pt 13 dt 2 title 'mix0.75', \
     'tiny-light.dat' index 5 using 1:2 with linespoints lc rgb '#2ca02c' pt 4 lw 2 title 'mis', \
     'tiny-light.dat' index 6 using 1:2 with linespoints lc rgb '#17becf' pt 6 lw 2 title 'mis-sobol', \
     'tiny-light.dat' index 7 using 1:2:(sprintf('q%d', $3)) with labels point pt 3 ps 1.5 lc rgb 'black' offset 0.8,0.6 font ',8' title 'POV-Ray', \
     'tiny-light.dat' index 8 using 1:2 with linespoints lc rgb '#000000' pt 2 dt 3 lw 2 title 'Mitsuba independent', \
     'tiny-light.dat' index 9 using 1:2 with linespoints lc rgb '#7f7f7f' pt 1 dt 3 lw 2 title 'Mitsuba multijitter'
reset
set output 'tiny-light-pure.png'
set title 'tiny-light-pure (128x128, median of seeds)'
set logscale xy
set format x '10^{%L}'
set format y '10^{%L}'
set xlabel 'render time (s)'
set ylabel 'relMSE'
set grid
set key outside right
plot 'tiny-light-pure.dat' index 0 using 1:2 with linespoints lc rgb '#d62728' pt 5 title 'material', \
     'tiny-light-pure.dat' index 1 using 1:2 with linespoints lc rgb '#1f77b4' pt 7 title 'light', \
     'tiny-light-pure.dat' index 2 using 1:2 with linespoints lc rgb '#ff7f0e' pt 9 dt 2 title 'mix0.25', \
     'tiny-light-pure.dat' index 3 using 1:2 with linespoints lc rgb '#9467bd' pt 11 dt 2 title 'mix0.5', \
     'tiny-light-pure.dat' index 4 using 1:2 with linespoints lc rgb '#8c564b' pt 13 dt 2 title 'mix0.75', \
     'tiny-light-pure.dat' index 5 using 1:2 with linespoints lc rgb '#2ca02c' pt 4 lw 2 title 'mis', \
     'tiny-light-pure.dat' index 6 using 1:2 with linespoints lc rgb '#17becf' pt 6 lw 2 title 'mis-sobol', \
     'tiny-light-pure.dat' index 7 using 1:2:(sprintf('q%d', $3)) with labels point pt 3 ps 1.5 lc rgb 'black' offset 0.8,0.6 font ',8' title 'POV-Ray', \
     'tiny-light-pure.dat' index 8 using 1:2 with linespoints lc rgb '#000000' pt 2 dt 3 lw 2 title 'Mitsuba independent', \
     'tiny-light-pure.dat' index 9 using 1:2 with linespoints lc rgb '#7f7f7f' pt 1 dt 3 lw 2 title 'Mitsuba multijitter'
reset
set output 'metal-glass.png'
set title 'metal-glass (128x128, median of seeds)'
set logscale xy
set format x '10^{%L}'
set format y '10^{%L}'
set xlabel 'render time (s)'
set ylabel 'relMSE'
set grid
set key outside right
plot 'metal-glass.dat' index 0 using 1:2 with linespoints lc rgb '#d62728' pt 5 title 'material', \
     'metal-glass.dat' index 1 using 1:2 with linespoints lc rgb '#1f77b4' pt 7 title 'light', \
     'metal-glass.dat' index 2 using 1:2 with linespoints lc rgb '#ff7f0e' pt 9 dt 2 title 'mix0.25', \
     'metal-glass.dat' index 3 using 1:2 with linespoints lc rgb '#9467bd' pt 11 dt 2 title 'mix0.5', \
     'metal-glass.dat' index 4 using 1:2 with linespoints lc rgb '#8c564b' pt 13 dt 2 title 'mix0.75', \
     'metal-glass.dat' index 5 using 1:2 with linespoints lc rgb '#2ca02c' pt 4 lw 2 title 'mis', \
     'metal-glass.dat' index 6 using 1:2 with linespoints lc rgb '#17becf' pt 6 lw 2 title 'mis-sobol', \
     'metal-glass.dat' index 7 using 1:2:(sprintf('q%d', $3)) with labels point pt 3 ps 1.5 lc rgb 'black' offset 0.8,0.6 font ',8' title 'POV-Ray', \
     'metal-glass.dat' index 8 using 1:2 with linespoints lc rgb '#000000' pt 2 dt 3 lw 2 title 'Mitsuba independent', \
     'metal-glass.dat' index 9 using 1:2 with linespoints lc rgb '#7f7f7f' pt 1 dt 3 lw 2 title 'Mitsuba multijitter'
reset
set output 'many-lights.png'
set title 'many-lights (128x128, median of seeds)'
set logscale xy
set format x '10^{%L}'
set format y '10^{%L}'
set xlabel 'render time (s)'
set ylabel 'relMSE'
set grid
set key outside right
plot 'many-lights.dat' index 0 using 1:2 with linespoints lc rgb '#d62728' pt 5 title 'material', \
     'many-lights.dat' index 1 using 1:2 with linespoints lc rgb '#1f77b4' pt 7 title 'light', \
     'many-lights.dat' index 2 using 1:2 with linespoints lc rgb '#ff7f0e' pt 9 dt 2 title 'mix0.25', \
     'many-lights.dat' index 3 using 1:2 with linespoints lc rgb '#9467bd' pt 11 dt 2 title 'mix0.5', \
     'many-lights.dat' index 4 using 1:2 with linespoints lc rgb '#8c564b' pt 13 dt 2 title 'mix0.75', \
     'many-lights.dat' index 5 using 1:2 with linespoints lc rgb '#2ca02c' pt 4 lw 2 title 'mis', \
     'many-lights.dat' index 6 using 1:2 with linespoints lc rgb '#17becf' pt 6 lw 2 title 'mis-sobol', \
     'many-lights.dat' index 7 using 1:2:(sprintf('q%d', $3)) with labels point pt 3 ps 1.5 lc rgb 'black' offset 0.8,0.6 font ',8' title 'POV-Ray', \
     'many-lights.dat' index 8 using 1:2 with linespoints lc rgb '#000000' pt 2 dt 3 lw 2 title 'Mitsuba independent', \
     'many-lights.dat' index 9 using 1:2 with linespoints lc rgb '#7f7f7f' pt 1 dt 3 lw 2 title 'Mitsuba multijitter'
reset
set output 'adaptive.png'
set title 'cornell: adaptive vs uniform sampling (MIS)'
set logscale xy
set format x '10^{%L}'
set format y '10^{%L}'
set grid
set xlabel 'render time (s)'
set ylabel 'relMSE'
plot 'adaptive.dat' index 0 using 1:2 with linespoints lc rgb '#2ca02c' pt 4 lw 2 title 'uniform', \
     'adaptive.dat' index 1 using 1:2 with linespoints lc rgb '#e377c2' pt 6 lw 2 title 'adaptive', \
     'adaptive.dat' index 2 using 1:2 with linespoints lc rgb '#7f7f7f' pt 8 lw 1 dt 2 title 'adaptive, neighbours only'
reset
set terminal pngcairo size 1500,900 font 'sans,10'
set output 'headline.png'
set multiplot layout 2,3 title 'pdftrace: relMSE against render time, 128x128, 2 cores (make bench)'
set title 'cornell (128x128, median of seeds)'
set logscale xy
set format x '10^{%L}'
set format y '10^{%L}'
set xlabel 'render time (s)'
set ylabel 'relMSE'
set grid
set key bottom left font ',8' spacing 0.8
plot 'cornell.dat' index 0 using 1:2 with linespoints lc rgb '#d62728' pt 5 title 'material', \
     'cornell.dat' index 1 using 1:2 with linespoints lc rgb '#1f77b4' pt 7 title 'light', \
     'cornell.dat' index 2 using 1:2 with linespoints lc rgb '#ff7f0e' pt 9 dt 2 title 'mix0.25', \
     'cornell.dat' index 3 using 1:2 with linespoints lc rgb '#9467bd' pt 11 dt 2 title 'mix0.5', \
     'cornell.dat' index 4 using 1:2 with linespoints lc rgb '#8c564b' pt 13 dt 2 title 'mix0.75', \
     'cornell.dat' index 5 using 1:2 with linespoints lc rgb '#2ca02c' pt 4 lw 2 title 'mis', \
     'cornell.dat' index 6 using 1:2 with linespoints lc rgb '#17becf' pt 6 lw 2 title 'mis-sobol', \
     'cornell.dat' index 7 using 1:2:(sprintf('q%d', $3)) with labels point pt 3 ps 1.5 lc rgb 'black' offset 0.8,0.6 font ',8' title 'POV-Ray', \
     'cornell.dat' index 8 using 1:2 with linespoints lc rgb '#000000' pt 2 dt 3 lw 2 title 'Mitsuba independent', \
     'cornell.dat' index 9 using 1:2 with linespoints lc rgb '#7f7f7f' pt 1 dt 3 lw 2 title 'Mitsuba multijitter'
set title 'tiny-light (128x128, median of seeds)'
set logscale xy
set format x '10^{%L}'
set format y '10^{%L}'
set xlabel 'render time (s)'
set ylabel 'relMSE'
set grid
set key bottom left font ',8' spacing 0.8
plot 'tiny-light.dat' index 0 using 1:2 with linespoints lc rgb '#d62728' pt 5 title 'material', \
     'tiny-light.dat' index 1 using 1:2 with linespoints lc rgb '#1f77b4' pt 7 title 'light', \
     'tiny-light.dat' index 2 using 1:2 with linespoints lc rgb '#ff7f0e' pt 9 dt 2 title 'mix0.25', \
     'tiny-light.dat' index 3 using 1:2 with linespoints lc rgb '#9467bd' pt 11 dt 2 title 'mix0.5', \
     'tiny-light.dat' index 4 using 1:2 with linespoints lc rgb '#8c564b' pt 13 dt 2 title 'mix0.75', \
     'tiny-light.dat' index 5 using 1:2 with linespoints lc rgb '#2ca02c' pt 4 lw 2 title 'mis', \
     'tiny-light.dat' index 6 using 1:2 with linespoints lc rgb '#17becf' pt 6 lw 2 title 'mis-sobol', \
     'tiny-light.dat' index 7 using 1:2:(sprintf('q%d', $3)) with labels point pt 3 ps 1.5 lc rgb 'black' offset 0.8,0.6 font ',8' title 'POV-Ray', \
     'tiny-light.dat' index 8 using 1:2 with linespoints lc rgb '#000000' pt 2 dt 3 lw 2 title 'Mitsuba independent', \
     'tiny-light.dat' index 9 using 1:2 with linespoints lc rgb '#7f7f7f' pt 1 dt 3 lw 2 title 'Mitsuba multijitter'
set title 'tiny-light-pure (128x128, median of seeds)'
set logscale xy
set format x '10^{%L}'
set format y '10^{%L}'
set xlabel 'render time (s)'
set ylabel 'relMSE'
set grid
set key bottom left font ',8' spacing 0.8
plot 'tiny-light-pure.dat' index 0 using 1:2 with linespoints lc rgb '#d62728' pt 5 title 'material', \
     'tiny-light-pure.dat' index 1 using 1:2 with linespoints lc rgb '#1f77b4' pt 7 title 'light', \
     'tiny-light-pure.dat' index 2 using 1:2 with linespoints lc rgb '#ff7f0e' pt 9 dt 2 title 'mix0.25', \
     'tiny-light-pure.dat' index 3 using 1:2 with linespoints lc rgb '#9467bd' pt 11 dt 2 title 'mix0.5', \
     'tiny-light-pure.dat' index 4 using 1:2 with linespoints lc rgb '#8c564b' pt 13 dt 2 title 'mix0.75', \
     'tiny-light-pure.dat' index 5 using 1:2 with linespoints lc rgb '#2ca02c' pt 4 lw 2 title 'mis', \
     'tiny-light-pure.dat' index 6 using 1:2 with linespoints lc rgb '#17becf' pt 6 lw 2 title 'mis-sobol', \
     'tiny-light-pure.dat' index 7 using 1:2:(sprintf('q%d', $3)) with labels point pt 3 ps 1.5 lc rgb 'black' offset 0.8,0.6 font ',8' title 'POV-Ray', \
     'tiny-light-pure.dat' index 8 using 1:2 with linespoints lc rgb '#000000' pt 2 dt 3 lw 2 title 'Mitsuba independent', \
     'tiny-light-pure.dat' index 9 using 1:2 with linespoints lc rgb '#7f7f7f' pt 1 dt 3 lw 2 title 'Mitsuba multijitter'
set title 'metal-glass (128x128, median of seeds)'
set logscale xy
set format x '10^{%L}'
set format y '10^{%L}'
set xlabel 'render time (s)'
set ylabel 'relMSE'
set grid
set key bottom left font ',8' spacing 0.8
plot 'metal-glass.dat' index 0 using 1:2 with linespoints lc rgb '#d62728' pt 5 title 'material', \
     'metal-glass.dat' index 1 using 1:2 with linespoints lc rgb '#1f77b4' pt 7 title 'light', \
     'metal-glass.dat' index 2 using 1:2 with linespoints lc rgb '#ff7f0e' pt 9 dt 2 title 'mix0.25', \
     'metal-glass.dat' index 3 using 1:2 with linespoints lc rgb '#9467bd' pt 11 dt 2 title 'mix0.5', \
     'metal-glass.dat' index 4 using 1:2 with linespoints lc rgb '#8c564b' pt 13 dt 2 title 'mix0.75', \
     'metal-glass.dat' index 5 using 1:2 with linespoints lc rgb '#2ca02c' pt 4 lw 2 title 'mis', \
     'metal-glass.dat' index 6 using 1:2 with linespoints lc rgb '#17becf' pt 6 lw 2 title 'mis-sobol', \
     'metal-glass.dat' index 7 using 1:2:(sprintf('q%d', $3)) with labels point pt 3 ps 1.5 lc rgb 'black' offset 0.8,0.6 font ',8' title 'POV-Ray', \
     'metal-glass.dat' index 8 using 1:2 with linespoints lc rgb '#000000' pt 2 dt 3 lw 2 title 'Mitsuba independent', \
     'metal-glass.dat' index 9 using 1:2 with linespoints lc rgb '#7f7f7f' pt 1 dt 3 lw 2 title 'Mitsuba multijitter'
set title 'many-lights (128x128, median of seeds)'
set logscale xy
set format x '10^{%L}'
set format y '10^{%L}'
set xlabel 'render time (s)'
set ylabel 'relMSE'
set grid
set key bottom left font ',8' spacing 0.8
plot 'many-lights.dat' index 0 using 1:2 with linespoints lc rgb '#d62728' pt 5 title 'material', \
     'many-lights.dat' index 1 using 1:2 with linespoints lc rgb '#1f77b4' pt 7 title 'light', \
     'many-lights.dat' index 2 using 1:2 with linespoints lc rgb '#ff7f0e' pt 9 dt 2 title 'mix0.25', \
     'many-lights.dat' index 3 using 1:2 with linespoints lc rgb '#9467bd' pt 11 dt 2 title 'mix0.5', \
     'many-lights.dat' index 4 using 1:2 with linespoints lc rgb '#8c564b' pt 13 dt 2 title 'mix0.75', \
     'many-lights.dat' index 5 using 1:2 with linespoints lc rgb '#2ca02c' pt 4 lw 2 title 'mis', \
     'many-lights.dat' index 6 using 1:2 with linespoints lc rgb '#17becf' pt 6 lw 2 title 'mis-sobol', \
     'many-lights.dat' index 7 using 1:2:(sprintf('q%d', $3)) with labels point pt 3 ps 1.5 lc rgb 'black' offset 0.8,0.6 font ',8' title 'POV-Ray', \
     'many-lights.dat' index 8 using 1:2 with linespoints lc rgb '#000000' pt 2 dt 3 lw 2 title 'Mitsuba independent', \
     'many-lights.dat' index 9 using 1:2 with linespoints lc rgb '#7f7f7f' pt 1 dt 3 lw 2 title 'Mitsuba multijitter'
set title 'cornell: adaptive vs uniform (MIS)'
plot 'adaptive.dat' index 0 using 1:2 with linespoints lc rgb '#2ca02c' pt 4 lw 2 title 'uniform', \
     'adaptive.dat' index 1 using 1:2 with linespoints lc rgb '#e377c2' pt 6 lw 2 title 'adaptive', \
     'adaptive.dat' index 2 using 1:2 with linespoints lc rgb '#7f7f7f' pt 8 lw 1 dt 2 title 'neighbours only'
unset multiplot
