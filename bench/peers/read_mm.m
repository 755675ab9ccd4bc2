function A = read_mm(f)
  % Reads a Matrix Market file (array or coordinate, real) as written by mbsgen's
  % write_matrix_market; coordinate files give a sparse matrix.
  fid = fopen(f, 'r');
  header = fgetl(fid);
  line = fgetl(fid);
  while numel(line) == 0 || line(1) == '%'
    line = fgetl(fid);
  end
  dims = sscanf(line, '%d');
  if ~isempty(strfind(header, 'coordinate'))
    d = fscanf(fid, '%d %d %g', [3, dims(3)])';
    A = sparse(d(:, 1), d(:, 2), d(:, 3), dims(1), dims(2));
  else
    d = fscanf(fid, '%g', dims(1) * dims(2));
    A = reshape(d, dims(1), dims(2));
  end
  fclose(fid);
end
