# drape_set_warnings(target): the project's warning set, errors when DRAPE_WERROR.
function(drape_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow)
  if(DRAPE_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
  if(DRAPE_SANITIZE)
    # Three of UBSan's checks are left out: they double the instrumented build
    # (engine/cloth/system.cpp compiles in 59 s with them, 27 s without; every
    # Eigen expression gets a null and an alignment check per reference) and
    # add little here: ASan reports a null dereference itself (SEGV at 0x0 with
    # the stack; a reference bound to null without a read goes unseen), a
    # misaligned access is no fault on x86-64 and the code does no type punning
    # of buffers, and vptr checks polymorphic casts the core has none of.
    # GCC's flow analysis under the sanitizers' instrumentation reports
    # maybe-uninitialized inside the standard library (std::regex's std::function
    # moves at -O1); the release build keeps the warning.
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined
      -fno-sanitize=alignment,null,vptr -fno-omit-frame-pointer -Wno-maybe-uninitialized)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
endfunction()
