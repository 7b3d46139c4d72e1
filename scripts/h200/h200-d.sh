source .devbin/setup.sh
export WGPU_ADAPTER_NAME=H200
timeout 400 $B/scheduler_gpu --test-threads 1 > $OUT/scheduler_gpu.txt 2>&1; echo "scheduler_gpu rc=$?" >> $OUT/scheduler_gpu.txt
timeout 150 $B/workloads_gpu --test-threads 1 > $OUT/workloads_gpu.txt 2>&1; echo "workloads_gpu rc=$?" >> $OUT/workloads_gpu.txt
grep -h "^test \|test result\|rc=" $OUT/*_gpu.txt
