# Runs CALIBRATE (`plydem calibrate ... --json`) and TENSION (`plydem tension ... --json`) on the
# same coupon and checks that calibrate reports the calibration the tension coupon got: for lattice
# that of the coupon's own packing (issue 14, item 4), entry for entry the same relaxed and target
# stiffness, and the coupon's size.
foreach(which CALIBRATE TENSION)
  execute_process(COMMAND ${${which}} RESULT_VARIABLE rc OUTPUT_VARIABLE out_${which}
                  ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${which} exit ${rc}:\n${out_${which}}${err}")
  endif()
endforeach()
string(JSON length GET "${out_CALIBRATE}" coupon length)
if(NOT length MATCHES "^0\\.000800000")
  message(FATAL_ERROR "calibrate reports a coupon length of ${length} m, not 0.0008")
endif()
foreach(matrix relaxed target)
  foreach(r 0 1 2)
    foreach(c 0 1 2)
      string(JSON mine GET "${out_CALIBRATE}" ${matrix} ${r} ${c})
      string(JSON coupon GET "${out_TENSION}" calibration ${matrix} ${r} ${c})
      if(NOT mine STREQUAL coupon)
        message(FATAL_ERROR "${matrix}[${r}][${c}]: calibrate ${mine}, the tension coupon ${coupon}")
      endif()
    endforeach()
  endforeach()
endforeach()
